#pragma once
// Between numpy arrays and the Eigen types of corocontact: every array handed to Python is a
// copy it owns (constant ones marked read-only); every array taken from Python is checked for
// its shape and copied.

#include <corocontact/core/types.hpp>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <string>
#include <vector>

namespace coro::python {

namespace py = pybind11;

/// A #rows×3 float64 array holding a copy of `rows`.
py::array_t<double> to_numpy(const Positions& rows);
/// A #rows×C int64 array holding a copy of `indices` (tets, faces).
template <int C>
py::array_t<std::int64_t> to_numpy(const Eigen::Matrix<Index, Eigen::Dynamic, C, Eigen::RowMajor>& indices);
/// A 1-D array holding a copy of `values`.
py::array_t<double> to_numpy(const std::vector<double>& values);
py::array_t<double> to_numpy(const VecX& values);
py::array_t<std::int64_t> to_numpy(const std::vector<Index>& values);
/// A 1-D numpy str array.
py::array to_numpy(const std::vector<std::string>& values);
/// A copy of the C-contiguous `array` that numpy refuses to make writable (for arrays cached
/// and handed out again).
py::array read_only(const py::array& array);

/// An N×3 array of numbers from any array-like: shape (rows, 3), or (3,) for the same row
/// everywhere.
/// @param[in] what  names the value in messages ("body 'left': velocities")
/// @throws InputError for another shape or non-numbers
Positions rows_from(const py::handle& object, Index rows, const std::string& what);
/// A 1-D array of `size` booleans from any array-like (non-zero counts as true).
std::vector<char> flags_from(const py::handle& object, Index size, const std::string& what);
/// A 3-vector of numbers.
Vec3 vec3_from(const py::handle& object, const std::string& what);
/// An M×C index array (C = 3 or 4 columns) of integers.
template <int C>
Eigen::Matrix<Index, Eigen::Dynamic, C, Eigen::RowMajor> indices_from(const py::handle& object,
                                                                      const std::string& what);

} // namespace coro::python
