// corocontact.detect and corocontact.detect_meshes: contact detection without a simulation.

#include "bindings.hpp"
#include "numpy_arrays.hpp"

#include <corocontact/core/error.hpp>

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <optional>

namespace coro::python {

using namespace pybind11::literals;

namespace {

/// One (vertices, faces or tets) pair of detect_meshes().
MeshInput mesh_from(const py::handle& item, std::size_t m, std::string name)
{
    const std::string source = "meshes[" + std::to_string(m) + "]";
    CORO_CHECK(py::isinstance<py::sequence>(item) && !py::isinstance<py::str>(item) && py::len(item) == 2, InputError,
               source << ": expected a pair (vertices, faces) or (vertices, tets)");
    const py::sequence pair = py::reinterpret_borrow<py::sequence>(item);
    MeshInput mesh;
    mesh.name = std::move(name);
    const py::array vertices = py::array::ensure(pair[0]);
    CORO_CHECK(vertices && vertices.ndim() == 2, InputError,
               source << ": vertices: expected an array of shape (N, 3)");
    mesh.vertices = rows_from(vertices, static_cast<Index>(vertices.shape(0)), source + ": vertices");
    const py::array cells = py::array::ensure(pair[1]);
    const bool tets = cells && cells.ndim() == 2 && cells.shape(1) == 4;
    if (tets)
        mesh.tets = indices_from<4>(cells, source + ": tets");
    else
        mesh.faces = indices_from<3>(pair[1], source + ": faces");
    return mesh;
}

} // namespace

py::dict rows_dict(const ContactRows& rows)
{
    std::vector<std::string> body, other;
    for (std::size_t r = 0; r < rows.body.size(); ++r) {
        body.push_back(rows.names[static_cast<std::size_t>(rows.body[r])]);
        other.push_back(rows.names[static_cast<std::size_t>(rows.other[r])]);
    }
    py::dict dict;
    dict["body"] = to_numpy(body);
    dict["vertex"] = to_numpy(rows.vertex);
    dict["other"] = to_numpy(other);
    dict["depth"] = to_numpy(rows.depth);
    dict["normal"] = to_numpy(rows.normal);
    dict["body_index"] = to_numpy(rows.body);
    dict["other_index"] = to_numpy(rows.other);
    dict["names"] = to_numpy(rows.names);
    return dict;
}

void bind_detection(py::module_& m)
{
    m.def(
        "detect",
        [](const std::filesystem::path& case_path, const std::string& mode) {
            std::vector<std::string> warnings;
            ContactRows rows;
            {
                py::gil_scoped_release release;
                rows = detect_case(case_path, mode, warnings);
            }
            warn(warnings);
            return rows_dict(rows);
        },
        "case_path"_a, "mode"_a = "exact",
        R"doc(Contact detection on the initial configuration of a case, as `corocontact detect CASE
--mode MODE --csv FILE` does it: a dict of numpy arrays with the CSV's columns body, vertex,
other, depth in its row order, plus normal (K×3), body_index, other_index and names (what
the indices refer to: bodies, mesh obstacles, planes). mode: "exact" or "paper". Bad input
raises InputError with the message of `corocontact detect`.)doc");

    m.def(
        "detect_meshes",
        [](const py::sequence& meshes, const std::string& mode, std::optional<std::vector<std::string>> names) {
            CORO_CHECK(!names || names->size() == py::len(meshes), InputError,
                       "names: expected one per mesh (" << py::len(meshes) << "), found " << names->size());
            std::vector<MeshInput> inputs;
            for (std::size_t i = 0; i < py::len(meshes); ++i)
                inputs.push_back(mesh_from(meshes[i], i, names ? (*names)[i] : "mesh" + std::to_string(i)));
            std::vector<std::string> warnings;
            ContactRows rows;
            {
                py::gil_scoped_release release;
                rows = detect_meshes(std::move(inputs), mode, warnings);
            }
            warn(warnings);
            return rows_dict(rows);
        },
        "meshes"_a, "mode"_a = "exact", "names"_a = py::none(),
        R"doc(Contact detection among your own meshes: every vertex of each mesh found inside another.

meshes  a list of (vertices, faces) pairs: vertices N×3 floats, faces F×3 vertex indices of a
        closed surface, counter-clockwise seen from outside; or (vertices, tets) with tets
        T×4, whose boundary is taken
mode    "exact" or "paper"
names   one name per mesh (default mesh0, mesh1, ...)

Returns the dict of detect(): body, vertex (row in that mesh's vertices), other, depth,
normal, body_index, other_index, names. Open surfaces are tested by the winding number and
inward-facing ones flipped, each with an InputWarning.)doc");
}

} // namespace coro::python
