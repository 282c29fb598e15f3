#include "numpy_arrays.hpp"

#include <corocontact/core/error.hpp>

#include <algorithm>
#include <cstring>
#include <limits>
#include <sstream>

namespace coro::python {

using namespace pybind11::literals;

namespace {

using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

std::string shape_of(const py::array& array)
{
    std::ostringstream text;
    text << "(";
    for (py::ssize_t d = 0; d < array.ndim(); ++d)
        text << (d > 0 ? ", " : "") << array.shape(d);
    text << (array.ndim() == 1 ? ",)" : ")");
    return text.str();
}

/// The type of `object` as Python names it ("list", "numpy.ndarray").
std::string type_name(const py::handle& object) { return py::str(py::type::of(object)).cast<std::string>(); }

/// `object` as a numpy array of real numbers (dtype kinds integer, unsigned, float, and bool
/// where `bools` says so), not yet converted: strings, complex numbers, dates, objects and
/// masked arrays are refused rather than converted by numpy's casts.
py::array real_array(const py::handle& object, const std::string& what, bool bools)
{
    const py::module_ numpy = py::module_::import("numpy");
    CORO_CHECK(!py::isinstance(object, numpy.attr("ma").attr("MaskedArray")), InputError,
               what << ": expected an array of numbers, found a masked array (fill it first: numpy.ma.filled)");
    const py::array array = py::array::ensure(object);
    CORO_CHECK(array, InputError, what << ": expected an array of numbers, found " << type_name(object));
    const char kind = array.dtype().kind();
    CORO_CHECK(kind == 'f' || kind == 'i' || kind == 'u' || (bools && kind == 'b'), InputError,
               what << ": expected an array of " << (bools ? "booleans or numbers" : "numbers (integers or floats)")
                    << ", found dtype " << py::str(array.dtype()).cast<std::string>());
    return array;
}

DoubleArray numbers_from(const py::handle& object, const std::string& what, bool bools = false)
{
    const py::array any = real_array(object, what, bools);
    DoubleArray array = DoubleArray::ensure(any);
    CORO_CHECK(array, InputError, what << ": numpy could not convert the array of shape " << shape_of(any)
                                       << " to float64 (out of memory?)");
    return array;
}

} // namespace

py::array_t<double> to_numpy(const Positions& rows)
{
    py::array_t<double> array({static_cast<py::ssize_t>(rows.rows()), py::ssize_t{3}});
    if (rows.size() > 0)
        std::memcpy(array.mutable_data(), rows.data(), sizeof(double) * static_cast<std::size_t>(rows.size()));
    return array;
}

template <int C>
py::array_t<std::int64_t> to_numpy(const Eigen::Matrix<Index, Eigen::Dynamic, C, Eigen::RowMajor>& indices)
{
    py::array_t<std::int64_t> array({static_cast<py::ssize_t>(indices.rows()), py::ssize_t{C}});
    std::int64_t* out = array.mutable_data();
    for (Eigen::Index i = 0; i < indices.size(); ++i)
        out[i] = indices.data()[i];
    return array;
}
template py::array_t<std::int64_t> to_numpy<3>(const Tris&);
template py::array_t<std::int64_t> to_numpy<4>(const Tets&);

py::array_t<double> to_numpy(const std::vector<double>& values)
{
    py::array_t<double> array(static_cast<py::ssize_t>(values.size()));
    std::copy(values.begin(), values.end(), array.mutable_data());
    return array;
}

py::array_t<double> to_numpy(const VecX& values)
{
    py::array_t<double> array(static_cast<py::ssize_t>(values.size()));
    std::copy(values.data(), values.data() + values.size(), array.mutable_data());
    return array;
}

py::array_t<std::int64_t> to_numpy(const std::vector<Index>& values)
{
    py::array_t<std::int64_t> array(static_cast<py::ssize_t>(values.size()));
    std::copy(values.begin(), values.end(), array.mutable_data());
    return array;
}

py::array to_numpy(const std::vector<std::string>& values)
{
    py::list list;
    for (const std::string& value : values)
        list.append(value);
    return py::module_::import("numpy").attr("array")(list, "dtype"_a = "str");
}

py::array read_only(const py::array& array)
{
    // Over a bytes object, which is immutable: numpy refuses to make the array, or any array
    // it derives from or that derives from it, writable again.
    const py::bytes bytes(static_cast<const char*>(array.data()), static_cast<std::size_t>(array.nbytes()));
    return py::module_::import("numpy").attr("frombuffer")(bytes, array.dtype()).attr("reshape")(array.attr("shape"));
}

Positions rows_from(const py::handle& object, Index rows, const std::string& what)
{
    const DoubleArray array = numbers_from(object, what);
    const bool one_row = array.ndim() == 1 && array.shape(0) == 3;
    CORO_CHECK(one_row || (array.ndim() == 2 && array.shape(0) == rows && array.shape(1) == 3), InputError,
               what << ": expected an array of shape (" << rows << ", 3), or one of shape (3,) for every row, found "
                    << shape_of(array));
    Positions result(rows, 3);
    if (one_row)
        result.rowwise() = Eigen::RowVector3d(array.at(0), array.at(1), array.at(2));
    else if (rows > 0)
        std::memcpy(result.data(), array.data(), sizeof(double) * static_cast<std::size_t>(result.size()));
    return result;
}

std::vector<char> flags_from(const py::handle& object, Index size, const std::string& what)
{
    const DoubleArray array = numbers_from(object, what, true);
    CORO_CHECK(array.ndim() == 1 && array.shape(0) == size, InputError,
               what << ": expected an array of shape (" << size << ",), found " << shape_of(array));
    std::vector<char> flags(static_cast<std::size_t>(size));
    for (Index i = 0; i < size; ++i) {
        const double value = array.at(i);
        CORO_CHECK(value == 0.0 || value == 1.0, InputError,
                   what << "[" << i << "] = " << value << ": expected True or False (or 1 or 0)");
        flags[static_cast<std::size_t>(i)] = value == 1.0 ? 1 : 0;
    }
    return flags;
}

Vec3 vec3_from(const py::handle& object, const std::string& what)
{
    const DoubleArray array = numbers_from(object, what);
    CORO_CHECK(array.ndim() == 1 && array.shape(0) == 3, InputError,
               what << ": expected an array of 3 numbers, found shape " << shape_of(array));
    return Vec3(array.at(0), array.at(1), array.at(2));
}

template <int C>
Eigen::Matrix<Index, Eigen::Dynamic, C, Eigen::RowMajor> indices_from(const py::handle& object, const std::string& what)
{
    const py::array any = py::array::ensure(object);
    CORO_CHECK(any && (any.dtype().kind() == 'i' || any.dtype().kind() == 'u'), InputError,
               what << ": expected an array of integers, found "
                    << (any ? "dtype " + py::str(any.dtype()).cast<std::string>() : type_name(object)));
    const auto array = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>::ensure(any);
    CORO_CHECK(array, InputError, what << ": numpy could not convert the array of shape " << shape_of(any)
                                       << " to int64 (out of memory?)");
    CORO_CHECK(array.ndim() == 2 && array.shape(1) == C, InputError,
               what << ": expected an array of shape (M, " << C << "), found " << shape_of(array));
    Eigen::Matrix<Index, Eigen::Dynamic, C, Eigen::RowMajor> result(array.shape(0), C);
    const std::int64_t* in = array.data();
    for (Eigen::Index i = 0; i < result.size(); ++i) {
        CORO_CHECK(in[i] >= 0 && in[i] <= std::numeric_limits<Index>::max(), InputError,
                   what << "[" << i / C << ", " << i % C << "] = " << in[i] << ": expected an index >= 0 and <= "
                        << std::numeric_limits<Index>::max());
        result.data()[i] = static_cast<Index>(in[i]);
    }
    return result;
}
template Tris indices_from<3>(const py::handle&, const std::string&);
template Tets indices_from<4>(const py::handle&, const std::string&);

} // namespace coro::python
