// The Python module corocontact: scripted runs of case files, results as numpy arrays, and
// contact detection on a case or on the caller's own meshes (docs/python.md).

#include "bindings.hpp"

#include <corocontact/config.hpp>
#include <corocontact/core/error.hpp>

namespace coro::python {

namespace {
// Made once at import and never released: the module keeps them for the interpreter's lifetime.
py::handle g_input_warning, g_output_warning;

py::handle new_warning(py::module_& m, const char* name, const char* doc)
{
    const std::string full = std::string("corocontact.") + name;
    const py::handle category(PyErr_NewExceptionWithDoc(full.c_str(), doc, PyExc_UserWarning, nullptr));
    if (!category)
        throw py::error_already_set();
    m.attr(name) = category;
    return category;
}
} // namespace

void warn(const std::vector<std::string>& warnings, WarningKind kind)
{
    const py::handle category = kind == WarningKind::INPUT ? g_input_warning : g_output_warning;
    for (const std::string& warning : warnings)
        if (PyErr_WarnEx(category.ptr(), warning.c_str(), 1) != 0)
            throw py::error_already_set();
}

} // namespace coro::python

PYBIND11_MODULE(corocontact, m)
{
    namespace py = pybind11;
    using namespace coro::python;
    m.doc() = "corocontact: co-rotational FEM bodies in contact, from Python (docs/python.md)";
    m.attr("__version__") = CORO_VERSION;
    // Bad input (exit code 2 of the command), divergence (3) and output that cannot be written
    // (4), with the command's messages.
    py::register_exception<coro::InputError>(m, "InputError", PyExc_ValueError);
    py::register_exception<coro::NumericalError>(m, "NumericalError", PyExc_RuntimeError);
    py::register_exception<coro::OutputError>(m, "OutputError", PyExc_OSError);
    g_input_warning = new_warning(m, "InputWarning", "What the corocontact command warns about its input.");
    g_output_warning = new_warning(m, "OutputWarning",
                                   "What the corocontact command tells about its output folder (a stale lock "
                                   "taken over, files of an earlier run removed).");
    bind_simulation(m);
    bind_detection(m);
}
