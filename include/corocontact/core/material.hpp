#pragma once
/// @file material.hpp
/// @brief Isotropic linear elastic material.

namespace coro {

/// Isotropic linear elastic material; units are those of the case (SI in the examples).
struct Material {
    double young = 1e5;     ///< Young's modulus E [Pa], > 0
    double poisson = 0.3;   ///< Poisson's ratio ν, in (−1, 0.5)
    double density = 1000.0; ///< mass density ρ [kg/m³], > 0

    /// First Lamé parameter λ = Eν/((1+ν)(1−2ν)).
    double lambda() const { return young * poisson / ((1.0 + poisson) * (1.0 - 2.0 * poisson)); }
    /// Shear modulus μ = E/(2(1+ν)).
    double mu() const { return young / (2.0 * (1.0 + poisson)); }
};

} // namespace coro
