#pragma once
/// @file contact_response.hpp
/// @brief Penalty contact response (DESIGN.md, Contact response): forces and the matrix terms
/// they add to one linearly implicit Euler step.
///
/// A contact couples the nodes that carry its two points: the penetrating vertex (share −1)
/// and the barycentric point of the other body's face (shares w_i), or a rigid obstacle. With
/// c the shares, n the other surface's outward normal and g ≥ 0 the depth, the gap is
/// g = n·Σ c_k x_k; the penetrating side gets F = k g n + c_n (n·u) n + F_t with u = Σ c_k v_k,
/// and node k gets −c_k F, so the forces of a contact sum to zero. Implicit Euler linearises
/// F around the step start: h² k (c cᵀ ⊗ n nᵀ) and h c_n (c cᵀ ⊗ n nᵀ) enter the matrix.
/// Friction is regularised Coulomb, implicit with a lagged coefficient: F_t = η u_t⁺ with
/// η = μ k g / max(|u_t|, ε) from the step start, i.e. h η (c cᵀ ⊗ (I − n nᵀ)) in the matrix:
/// a slipping contact feels |F_t| ≈ μ k g against its slip, one slower than ε sticks.

#include <corocontact/contact/contact_surface.hpp>
#include <corocontact/contact/detector.hpp>
#include <corocontact/sim/body.hpp>
#include <corocontact/sim/case_spec.hpp>
#include <corocontact/solver/scene_matrix.hpp>

#include <vector>

namespace coro {

/// Speed [m/s] below which friction sticks (regularised Coulomb).
constexpr double FRICTION_STICK_SPEED = 1e-3;

/// What contact adds to one implicit Euler step of the scene: explicit forces per body, and
/// the coupling blocks of the scene matrix.
class ContactResponse {
public:
    /// Builds the response of every contact point, in parallel over the contacts; every
    /// contact writes its own slots, which are then added in contact order, so forces and blocks
    /// never depend on the thread count. Buffers are kept between calls (no allocation once they
    /// have held a step's contacts).
    /// @param[in] bodies    the scene's bodies (velocities and fixed nodes are read)
    /// @param[in] surfaces  surfaces of the bodies (same order), then of static obstacles
    /// @param[in] contacts  detection output (surfaces and plane obstacles, see ContactTarget)
    /// @param[in] dt        the step h [s]
    /// @param[in,out] matrix  the scene matrix whose coupling() is refilled and finished;
    ///                        blocks in rows or columns of fixed nodes are left out
    void compute(const std::vector<Body>& bodies, const std::vector<ContactSurface>& surfaces,
                 const std::vector<ContactPoint>& contacts, const ContactSettings& settings, double dt,
                 SceneMatrix& matrix);

    /// Per body, #3V: explicit contact forces at the step start (penalty) [N]; empty before
    /// the first compute().
    const std::vector<VecX>& forces() const { return m_forces; }

private:
    /// A node carrying part of a contact point, with its barycentric coefficient.
    struct Share {
        Index body = 0;
        Index node = 0;
        double coefficient = 0.0;
    };
    std::vector<VecX> m_forces;
    std::vector<Index> m_share_offsets; // #contacts+1 into m_shares
    std::vector<Index> m_block_offsets; // #contacts+1 into the coupling entries
    std::vector<Share> m_shares;
    std::vector<Vec3> m_share_forces;   // force on each share's node [N]
};

} // namespace coro
