#pragma once
/// @file phase_times.hpp
/// @brief Wall time spent per phase of a step, and a scoped timer that adds to it.

#include <chrono>

namespace coro {

/// Seconds spent per phase (DESIGN.md, summary `phases`).
struct PhaseTimes {
    double rotation = 0.0; ///< element rotations R_e
    double assembly = 0.0; ///< rotated stiffness, internal forces, right-hand side
    double solve = 0.0;    ///< PCG
    double contact = 0.0;  ///< contact detection and response
    double output = 0.0;   ///< VTK frames

    double total() const { return rotation + assembly + solve + contact + output; }
};

/// Adds the lifetime of the object, in seconds, to `target`.
class ScopedTimer {
public:
    explicit ScopedTimer(double& target) : m_target(target), m_start(std::chrono::steady_clock::now()) {}
    ~ScopedTimer()
    {
        m_target += std::chrono::duration<double>(std::chrono::steady_clock::now() - m_start).count();
    }
    ScopedTimer(const ScopedTimer&) = delete;
    ScopedTimer& operator=(const ScopedTimer&) = delete;

private:
    double& m_target;
    std::chrono::steady_clock::time_point m_start;
};

} // namespace coro
