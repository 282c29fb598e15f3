// corocontact.Simulation and corocontact.Body: a case stepped from Python.

#include "bindings.hpp"
#include "case_run.hpp"
#include "contact_rows.hpp"
#include "numpy_arrays.hpp"

#include <corocontact/core/error.hpp>
#include <corocontact/core/surface_mesh.hpp>

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <atomic>
#include <cstring>
#include <memory>
#include <optional>

namespace coro::python {

using namespace pybind11::literals;

namespace {

/// A CaseRun shared by a Simulation and its Body objects. While step() runs (without the GIL),
/// every other call on it from another Python thread raises RuntimeError instead of reading a
/// state that is being written.
class SharedRun {
public:
    SharedRun(const std::filesystem::path& case_file, std::optional<Index> threads,
              const std::filesystem::path& output_dir)
        : m_run(case_file, threads, output_dir)
    {
    }
    /// The run, for any call but step().
    CaseRun& get()
    {
        if (m_stepping.load())
            throw std::runtime_error("this Simulation is stepping in another thread; call it when step() has returned");
        return m_run;
    }
    /// step(n): the GIL is released during each step and taken between steps, to let Ctrl-C in.
    void step(Index n)
    {
        CORO_CHECK(n >= 0, InputError, "step(n = " << n << "): expected n >= 0");
        CaseRun& run = get();
        run.check_can_step(n);
        for (Index i = 0; i < n; ++i) {
            {
                Stepping stepping(m_stepping);
                py::gil_scoped_release release;
                run.step();
            }
            if (PyErr_CheckSignals() != 0)
                throw py::error_already_set();
        }
    }

private:
    struct Stepping {
        explicit Stepping(std::atomic<bool>& flag) : m_flag(flag)
        {
            if (m_flag.exchange(true))
                throw std::runtime_error("this Simulation is stepping in another thread");
        }
        ~Stepping() { m_flag.store(false); }
        Stepping(const Stepping&) = delete;
        Stepping& operator=(const Stepping&) = delete;
        std::atomic<bool>& m_flag;
    };
    CaseRun m_run;
    std::atomic<bool> m_stepping{false};
};

/// pybind11 (2.10; its issue #6153) gives the methods of an object made by `Class.__new__(Class)`
/// without __init__ storage from the class's operator new that no constructor has run on.
/// Zeroed, its null shared pointer lets every method refuse the object instead of reading garbage.
struct ZeroedStorage {
    static void* operator new(std::size_t size)
    {
        void* storage = ::operator new(size);
        std::memset(storage, 0, size);
        return storage;
    }
    static void operator delete(void* storage) { ::operator delete(storage); }
};

/// The run `run` points to; TypeError for an object __init__ never ran on (see ZeroedStorage).
SharedRun& constructed(const std::shared_ptr<SharedRun>& run, const char* type)
{
    if (!run)
        throw py::type_error(std::string("this corocontact.") + type + " was made by " + type +
                             ".__new__ without __init__; use " +
                             (std::string(type) == "Body" ? "Simulation(case_path).bodies" : "Simulation(case_path)"));
    return *run;
}

/// One body of a Simulation. Constant arrays (rest positions, tets, faces, masses) are made
/// once and handed out read-only; state arrays are fresh copies at every access.
class BodyView : public ZeroedStorage {
public:
    BodyView(std::shared_ptr<SharedRun> run, Index index) : m_run(std::move(run)), m_index(index) {}

    const Body& body() const { return run().scene().bodies[static_cast<std::size_t>(m_index)]; }
    CaseRun& run() const { return constructed(m_run, "Body").get(); }
    Index index() const { return m_index; }
    std::string what(const char* attribute) const { return "body '" + body().name() + "': " + attribute; }

    py::object rest_positions()
    {
        if (!m_rest_positions)
            m_rest_positions = read_only(to_numpy(body().to_input_order(body().fem().rest_dofs())));
        return m_rest_positions;
    }
    py::object tets()
    {
        if (!m_tets)
            m_tets = read_only(to_numpy(body().input_tets()));
        return m_tets;
    }
    py::object surface_faces()
    {
        if (!m_faces) {
            const TetMesh input{body().to_input_order(body().fem().rest_dofs()), body().input_tets()};
            m_faces = read_only(to_numpy(boundary_faces(input)));
        }
        return m_faces;
    }
    py::object masses()
    {
        if (!m_masses) {
            const VecX& internal = body().fem().lumped_masses();
            VecX masses(internal.size());
            for (Index v = 0; v < body().num_vertices(); ++v)
                masses[body().input_node(v)] = internal[v];
            m_masses = read_only(to_numpy(masses));
        }
        return m_masses;
    }

private:
    std::shared_ptr<SharedRun> m_run;
    Index m_index;
    py::object m_rest_positions, m_tets, m_faces, m_masses;
};

/// The Python side of a Simulation: the shared run and its Body objects.
struct SimulationObject : ZeroedStorage {
    SharedRun& shared() const { return constructed(run, "Simulation"); }
    std::shared_ptr<SharedRun> run;
    py::tuple bodies;
};

/// Warns, before a change of the body's loads or fixed nodes (input order, null: unchanged),
/// when the loads would fall on fixed nodes; a warnings filter that makes the warning an error
/// stops the change before it is made.
void warn_about_loads_on_fixed_nodes(BodyView& view, const Positions* loads, const std::vector<char>* fixed)
{
    if (const auto warning = view.run().loads_on_fixed_nodes(view.index(), loads, fixed))
        warn({*warning});
}

const char* analysis_name(Analysis analysis) { return analysis == Analysis::STATIC ? "static" : "dynamic"; }

py::tuple make_bodies(const std::shared_ptr<SharedRun>& run)
{
    const auto n = run->get().scene().bodies.size();
    py::tuple bodies(n);
    for (std::size_t b = 0; b < n; ++b)
        bodies[b] = py::cast(BodyView(run, static_cast<Index>(b)));
    return bodies;
}

} // namespace

void bind_simulation(py::module_& m)
{
    py::class_<BodyView>(m, "Body", R"doc(One body of a Simulation (obtained from Simulation.bodies).

Node arrays are in the input order: row i is node i of the body's mesh file (or of the
generated box/sphere), whatever order the solver keeps internally. State arrays (positions,
velocities, ...) are copies made at each access: writing to them changes nothing; assign the
attribute to change the body. Constant arrays (rest_positions, tets, surface_faces, masses) are
read-only arrays shared between accesses.)doc")
        .def_property_readonly("name", [](const BodyView& self) { return self.body().name(); })
        .def_property_readonly("index", &BodyView::index, "position in Simulation.bodies")
        .def_property_readonly("num_vertices", [](const BodyView& self) { return self.body().num_vertices(); })
        .def_property_readonly("num_tets", [](const BodyView& self) { return self.body().mesh().num_tets(); })
        .def_property(
            "positions", [](const BodyView& self) { return to_numpy(self.body().to_input_order(self.body().positions())); },
            nullptr, "current node positions, N×3 float64 [m] (a copy)")
        .def_property(
            "velocities",
            [](const BodyView& self) { return to_numpy(self.body().to_input_order(self.body().velocities())); },
            [](BodyView& self, const py::handle& value) {
                self.run().set_velocities(self.index(),
                                          rows_from(value, self.body().num_vertices(), self.what("velocities")));
            },
            R"doc(node velocities, N×3 float64 [m/s] (a copy). Assign an N×3 array (or one 3-vector for
every node) to change them; fixed nodes must get 0.)doc")
        .def_property_readonly("rest_positions", &BodyView::rest_positions,
                               "node positions at rest after the body transform, N×3 float64 [m] (read-only)")
        .def_property_readonly("tets", &BodyView::tets,
                               "tets in input order, M×4 int64 node indices, positively oriented (read-only)")
        .def_property_readonly("surface_faces", &BodyView::surface_faces,
                               "boundary triangles of the tets, F×3 int64 node indices, outward (read-only)")
        .def_property_readonly("masses", &BodyView::masses, "lumped node masses, N float64 [kg] (read-only)")
        .def_property(
            "fixed",
            [](const BodyView& self) {
                const Body& body = self.body();
                py::array_t<bool> fixed(body.num_vertices());
                for (Index v = 0; v < body.num_vertices(); ++v)
                    fixed.mutable_at(body.input_node(v)) = body.fixed()[static_cast<std::size_t>(v)] != 0;
                return fixed;
            },
            [](BodyView& self, const py::handle& value) {
                const std::vector<char> fixed = flags_from(value, self.body().num_vertices(), self.what("fixed"));
                self.run().check_fixed(self.index(), fixed);
                warn_about_loads_on_fixed_nodes(self, nullptr, &fixed);
                self.run().set_fixed(self.index(), fixed);
            },
            R"doc(N bool, True for a node held in place (a copy). Assign an N-array to change it: nodes
fixed from now on stay where they are (velocity 0); released ones move from the next step.)doc")
        .def_property(
            "loads",
            [](const BodyView& self) { return to_numpy(self.body().to_input_order(self.body().load_forces())); },
            [](BodyView& self, const py::handle& value) {
                const Positions loads = rows_from(value, self.body().num_vertices(), self.what("loads"));
                self.run().check_loads(self.index(), loads);
                warn_about_loads_on_fixed_nodes(self, &loads, nullptr);
                self.run().set_loads(self.index(), loads);
            },
            R"doc(constant external node forces, N×3 float64 [N] (a copy; the case's [[body.load]] boxes
split over their nodes). Assign an N×3 array to change them. Gravity is separate
(Simulation.gravity).)doc")
        .def_property_readonly(
            "contact_forces",
            [](const BodyView& self) {
                const Scene& scene = self.run().scene();
                const auto b = static_cast<std::size_t>(self.index());
                const Body& body = self.body();
                return to_numpy(body.to_input_order(b < scene.contact_forces.size() ? scene.contact_forces[b]
                                                                                    : VecX::Zero(3 * body.num_vertices())));
            },
            "contact forces of the last detection on the nodes, N×3 float64 [N] (a copy; contact_force in the frames)")
        .def_property_readonly(
            "von_mises",
            [](const BodyView& self) {
                const Body& body = self.body();
                const VecX internal = body.fem().von_mises_stress(body.positions());
                VecX stress(internal.size());
                for (Index t = 0; t < body.mesh().num_tets(); ++t)
                    stress[body.input_tet(t)] = internal[t];
                return to_numpy(stress);
            },
            "von Mises stress per tet, M float64 [Pa] in input tet order (a copy)")
        .def("__repr__", [](const BodyView& self) {
            return "<corocontact.Body '" + self.body().name() + "': " + std::to_string(self.body().num_vertices()) +
                   " nodes, " + std::to_string(self.body().mesh().num_tets()) + " tets>";
        });

    py::class_<SimulationObject>(m, "Simulation", R"doc(A case file loaded exactly as `corocontact run` loads it, stepped from Python.

Simulation(case_path, threads=None, output_dir=None)

case_path   the .toml case file
threads     worker threads (a tbb::global_control held as long as this object lives; TBB
            takes the smallest limit when several are alive); None: all cores
output_dir  where write_frame() and write_summary() write (like `run --out`); None: the
            case's simulation.output_dir

Bad input raises InputError with the message `corocontact run` prints (exit code 2);
warnings while loading come as InputWarning. The initial detection runs here, so
`contacts` is the contact state before the first step.)doc")
        .def(py::init([](const std::filesystem::path& case_path, std::optional<Index> threads,
                         std::optional<std::filesystem::path> output_dir) {
                 CORO_CHECK(!output_dir || !output_dir->empty(), InputError,
                            "output_dir = '': expected a path, or None for the case's simulation.output_dir");
                 SimulationObject object;
                 {
                     py::gil_scoped_release release; // loading a large case takes a while
                     object.run = std::make_shared<SharedRun>(case_path, threads,
                                                              output_dir ? *output_dir : std::filesystem::path());
                 }
                 object.bodies = make_bodies(object.run);
                 warn(object.run->get().load_warnings());
                 return object;
             }),
             "case_path"_a, "threads"_a = py::none(), "output_dir"_a = py::none())
        .def(
            "step", [](SimulationObject& self, Index n) { self.shared().step(n); }, "n"_a = 1,
            R"doc(Advances n time steps (a static analysis: n load steps). The GIL is released during
each step. Raises NumericalError when the simulation diverges ("step N (t = ...): ..."), the
message `corocontact run` prints with exit code 3; from then on step() and write_frame() raise it
again (the state is what the failed step left). In a static analysis, n beyond the load steps
left raises InputError before any step.)doc")
        .def_property_readonly("time", [](SimulationObject& self) { return self.shared().get().time(); },
                               "simulated time after steps_done steps [s] (static: the load factor)")
        .def_property_readonly("steps_done", [](SimulationObject& self) { return self.shared().get().steps_done(); })
        .def_property_readonly("bodies", [](SimulationObject& self) { self.shared(); return self.bodies; },
                               "the bodies, in case order (a tuple of Body)")
        .def(
            "body",
            [](SimulationObject& self, const std::string& name) -> py::object {
                self.shared();
                for (const py::handle body : self.bodies)
                    if (body.cast<const BodyView&>().body().name() == name)
                        return py::reinterpret_borrow<py::object>(body);
                throw py::key_error("no body named '" + name + "'");
            },
            "name"_a, "the body with this name")
        .def_property_readonly(
            "contacts",
            [](SimulationObject& self) {
                const Scene& scene = self.shared().get().scene();
                return rows_dict(contact_rows(scene.surfaces, static_cast<Index>(scene.planes.size()), scene.contacts));
            },
            R"doc(what the last detection found (the initial state before the first step): a dict of
numpy arrays, one row per surface vertex inside another body or obstacle, in the order of
`corocontact detect --csv`: body, other (names), vertex (node index in the body's mesh file;
in its surface file for an embedded surface), depth [m], normal (outward unit normal of the
other surface, K×3), body_index and other_index (into names: the bodies, then mesh
obstacles obstacle<k>, then planes plane<k>). Copies.)doc")
        .def(
            "write_frame",
            [](SimulationObject& self) {
                CaseRun& run = self.shared().get();
                const std::filesystem::path pvd = run.write_frame();
                warn(run.take_output_notes(), WarningKind::OUTPUT);
                return pvd;
            },
            R"doc(Writes the current state as frame `steps_done` of OUT/NAME.pvd, exactly as `corocontact
run` writes its frames (it writes frame 0, every output_every-th step and the last). Returns
the .pvd path. The first write takes the output folder's lock (OUT/corocontact.lock, held
while this object lives) and removes what an earlier run of the series left there, as
`corocontact run` does; OutputError if another run holds the folder or a file cannot be
written.)doc")
        .def(
            "summary", [](SimulationObject& self) { return py::module_::import("json").attr("loads")(self.shared().get().summary_json()); },
            "the counters so far as a dict, with the keys of OUT/NAME.summary.json")
        .def(
            "write_summary",
            [](SimulationObject& self) {
                CaseRun& run = self.shared().get();
                const std::filesystem::path path = run.write_summary();
                warn(run.take_output_notes(), WarningKind::OUTPUT);
                return path;
            },
            "writes OUT/NAME.summary.json as `corocontact run` does at its end; returns its path")
        .def_property(
            "gravity", [](SimulationObject& self) { return to_numpy(VecX(self.shared().get().spec().simulation.gravity)); },
            [](SimulationObject& self, const py::handle& value) { self.shared().get().set_gravity(vec3_from(value, "gravity")); },
            "[simulation] gravity, 3 float64 [m/s²] (a copy); assign to change it")
        .def_property_readonly("contact_enabled", [](SimulationObject& self) { return self.shared().get().spec().contact.enabled; })
        .def_property(
            "contact_stiffness", [](SimulationObject& self) { return self.shared().get().spec().contact.stiffness; },
            [](SimulationObject& self, double value) { self.shared().get().set_contact_stiffness(value); },
            "[contact] stiffness [N/m], > 0")
        .def_property(
            "contact_damping", [](SimulationObject& self) { return self.shared().get().spec().contact.damping; },
            [](SimulationObject& self, double value) { self.shared().get().set_contact_damping(value); },
            "[contact] damping [N·s/m], >= 0")
        .def_property(
            "contact_friction", [](SimulationObject& self) { return self.shared().get().spec().contact.friction; },
            [](SimulationObject& self, double value) { self.shared().get().set_contact_friction(value); },
            "[contact] friction, the Coulomb coefficient, in [0, 10]")
        .def_property_readonly("name", [](SimulationObject& self) { return self.shared().get().spec().simulation.name; })
        .def_property_readonly("analysis", [](SimulationObject& self) { return analysis_name(self.shared().get().spec().simulation.analysis); })
        .def_property_readonly("dt", [](SimulationObject& self) { return self.shared().get().spec().simulation.dt; })
        .def_property_readonly(
            "last_step",
            [](SimulationObject& self) {
                const SimulationSettings& s = self.shared().get().spec().simulation;
                return s.analysis == Analysis::STATIC ? s.load_steps : s.steps;
            },
            "the step `corocontact run` stops at: simulation.steps (dynamic) or load_steps (static)")
        .def_property_readonly(
            "output_every",
            [](SimulationObject& self) {
                const SimulationSettings& s = self.shared().get().spec().simulation;
                return s.analysis == Analysis::STATIC ? 1 : s.output_every;
            },
            "`corocontact run` writes every output_every-th step: simulation.output_every (dynamic), 1 (static)")
        .def_property_readonly("output_dir", [](SimulationObject& self) { return self.shared().get().spec().simulation.output_dir; })
        .def_property_readonly("series_path", [](SimulationObject& self) { return self.shared().get().series_path(); },
                               "OUT/NAME.pvd, the series write_frame() writes")
        .def_property_readonly("threads", [](SimulationObject& self) { return self.shared().get().threads(); },
                               "worker threads TBB uses now")
        .def_property_readonly("warnings", [](SimulationObject& self) {
                                   py::list warnings;
                                   for (const std::string& warning : self.shared().get().load_warnings())
                                       warnings.append(text(warning));
                                   return warnings;
                               },
                               "the warnings of loading (also given as InputWarning)")
        .def("__repr__", [](SimulationObject& self) {
            CaseRun& run = self.shared().get();
            return "<corocontact.Simulation '" + run.spec().simulation.name + "': " +
                   std::to_string(run.scene().bodies.size()) + " bodies, step " + std::to_string(run.steps_done()) +
                   ">";
        });
}

} // namespace coro::python
