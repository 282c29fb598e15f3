#pragma once
/// @file exact_parity.hpp
/// @brief The inside test of last resort for a closed surface, exact in every case: whether the
/// point lies on the surface, else the parity of the faces that a segment from the point to a
/// point outside the surface crosses, with every orientation sign exact.

#include <corocontact/contact/contact_surface.hpp>

namespace coro::detail {

struct ParityTest {
    bool decided = false;    ///< false only if every segment tried met an edge or a vertex
    bool inside = false;     ///< strictly inside (the surface closed and consistently oriented)
    bool on_surface = false; ///< exactly on a face (then not inside)
};

/// The exact inside test of `point` against the closed, outward oriented `surface`: O(faces),
/// each sign found in floating point where its rounding bound settles it, else in rational
/// arithmetic. For the points that three axis lines leave undecided.
ParityTest exact_parity_test(const ContactSurface& surface, const Vec3& point);

} // namespace coro::detail
