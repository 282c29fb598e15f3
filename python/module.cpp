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

py::str text(const std::string& message)
{
    PyObject* decoded = PyUnicode_DecodeUTF8(message.data(), static_cast<Py_ssize_t>(message.size()), "replace");
    if (decoded == nullptr)
        throw py::error_already_set();
    return py::reinterpret_steal<py::str>(decoded);
}

void warn(const std::vector<std::string>& warnings, WarningKind kind)
{
    const py::handle category = kind == WarningKind::INPUT ? g_input_warning : g_output_warning;
    for (const std::string& warning : warnings)
        if (PyErr_WarnEx(category.ptr(), text(warning).cast<std::string>().c_str(), 1) != 0)
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
    // Messages may hold bytes that are not UTF-8 (a path's): decoded with U+FFFD for those.
    static py::exception<coro::InputError> input_error(m, "InputError", PyExc_ValueError);
    static py::exception<coro::NumericalError> numerical_error(m, "NumericalError", PyExc_RuntimeError);
    static py::exception<coro::OutputError> output_error(m, "OutputError", PyExc_OSError);
    py::register_exception_translator([](std::exception_ptr thrown) {
        const auto raise = [](const py::handle type, const std::exception& e) {
            PyErr_SetObject(type.ptr(), text(e.what()).ptr());
        };
        try {
            if (thrown)
                std::rethrow_exception(thrown);
        } catch (const coro::InputError& e) {
            raise(input_error, e);
        } catch (const coro::NumericalError& e) {
            raise(numerical_error, e);
        } catch (const coro::OutputError& e) {
            raise(output_error, e);
        }
    });
    g_input_warning = new_warning(m, "InputWarning", "What the corocontact command warns about its input.");
    g_output_warning = new_warning(m, "OutputWarning",
                                   "What the corocontact command tells about its output folder (a stale lock "
                                   "taken over, files of an earlier run removed).");
    bind_simulation(m);
    bind_detection(m);
}
