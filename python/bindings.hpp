#pragma once
// What the parts of the module share: the warning category and contact rows as a dict.

#include "contact_rows.hpp"

#include <pybind11/pybind11.h>

#include <string>
#include <vector>

namespace coro::python {

namespace py = pybind11;

/// Warning categories (UserWarning): what `corocontact` prints as "warning: ..." about its input
/// (InputWarning) and about its output folder (OutputWarning).
enum class WarningKind { INPUT, OUTPUT };
/// `message` as a Python str; bytes that are not UTF-8 (in a path) become U+FFFD.
py::str text(const std::string& message);
/// Gives each of `warnings` to Python's warnings module.
/// @throws py::error_already_set when a warnings filter turns them into errors
void warn(const std::vector<std::string>& warnings, WarningKind kind = WarningKind::INPUT);

/// Contact rows as the dict of numpy arrays that Simulation.contacts and detect() return:
/// body, vertex, other, depth (the columns of `corocontact detect --csv`), normal, body_index,
/// other_index, names.
py::dict rows_dict(const ContactRows& rows);

void bind_simulation(py::module_& m);
void bind_detection(py::module_& m);

} // namespace coro::python
