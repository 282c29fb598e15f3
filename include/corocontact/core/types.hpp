#pragma once
/// @file types.hpp
/// @brief The numeric vocabulary of corocontact: one place for every Eigen alias.

#include <Eigen/Dense>
#include <Eigen/SparseCore>

#include <cstdint>

namespace coro {

/// Index type of vertices, tets, faces and DOFs (32 bit: meshes stay below 2^31 entries).
using Index = std::int32_t;

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
/// One tet's 4×3 DOFs, node-major: [x0 y0 z0 x1 ... z3].
using Vec12 = Eigen::Matrix<double, 12, 1>;
/// One tet's stiffness: tests and reference paths only; never stored per element.
using Mat12 = Eigen::Matrix<double, 12, 12>;
/// Global DOFs [x0 y0 z0 x1 ...].
using VecX = Eigen::VectorXd;
/// #V×3 positions, row-major so that a VecX of DOFs maps onto it without a copy.
using Positions = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
/// #T×4 vertex indices of tetrahedra.
using Tets = Eigen::Matrix<Index, Eigen::Dynamic, 4, Eigen::RowMajor>;
/// #F×3 vertex indices of triangles.
using Tris = Eigen::Matrix<Index, Eigen::Dynamic, 3, Eigen::RowMajor>;
using SparseMat = Eigen::SparseMatrix<double, Eigen::RowMajor, Index>;

/// Read-only view of any Eigen object convertible to T (ipc's Eigen::ConstRef).
template <class T> using CRef = const Eigen::Ref<const T>&;

/// View a DOF vector as #V×3 positions (no copy).
inline Eigen::Map<Positions> as_positions(VecX& x) { return {x.data(), x.size() / 3, 3}; }
/// View a DOF vector as #V×3 positions (no copy, read-only).
inline Eigen::Map<const Positions> as_positions(const VecX& x) { return {x.data(), x.size() / 3, 3}; }
/// View #V×3 positions as a DOF vector (no copy).
inline Eigen::Map<VecX> as_dofs(Positions& p) { return {p.data(), p.size()}; }
/// View #V×3 positions as a DOF vector (no copy, read-only).
inline Eigen::Map<const VecX> as_dofs(const Positions& p) { return {p.data(), p.size()}; }

} // namespace coro
