// The Python module corocontact: scripted runs of case files, results as numpy arrays, and
// contact detection on a case or on the caller's own meshes (docs/python.md).

#include "bindings.hpp"

#include <corocontact/config.hpp>
#include <corocontact/core/error.hpp>

namespace coro::python {

namespace {
// Made once at import and never released: the module keeps it for the interpreter's lifetime.
py::handle g_input_warning;
} // namespace

py::handle input_warning() { return g_input_warning; }

void warn(const std::vector<std::string>& warnings)
{
    for (const std::string& warning : warnings)
        if (PyErr_WarnEx(g_input_warning.ptr(), warning.c_str(), 1) != 0)
            throw py::error_already_set();
}

} // namespace coro::python

PYBIND11_MODULE(corocontact, m)
{
    namespace py = pybind11;
    using namespace coro::python;
    m.doc() = "corocontact: co-rotational FEM bodies in contact, from Python (docs/python.md)";
    m.attr("__version__") = CORO_VERSION;
    // Bad input (exit code 2 of the command) and divergence (exit code 3), with the same messages.
    py::register_exception<coro::InputError>(m, "InputError", PyExc_ValueError);
    py::register_exception<coro::NumericalError>(m, "NumericalError", PyExc_RuntimeError);
    g_input_warning = py::handle(PyErr_NewExceptionWithDoc("corocontact.InputWarning",
                                  "What the corocontact command prints as 'warning: ...' while loading input.",
                                  PyExc_UserWarning, nullptr));
    if (!g_input_warning)
        throw py::error_already_set();
    m.attr("InputWarning") = g_input_warning;
    bind_simulation(m);
    bind_detection(m);
}
