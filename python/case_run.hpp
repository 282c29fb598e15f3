#pragma once
// The C++ side of corocontact.Simulation: a case loaded exactly as `corocontact run` loads it,
// stepped by the caller, with the inputs a script may change between steps. No Python here:
// simulation_binding.cpp turns arrays and errors into Python's.

#include <corocontact/io/output_lock.hpp>
#include <corocontact/io/scene_loader.hpp>
#include <corocontact/io/vtk_series.hpp>
#include <corocontact/sim/case_spec.hpp>
#include <corocontact/sim/simulation.hpp>

#include <tbb/global_control.h>

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace coro::python {

class CaseRun {
public:
    /// Reads the case (io/case_reader), builds its bodies (io/scene_loader) and runs the initial
    /// detection (Simulation::start), as `corocontact run` does.
    /// @param[in] case_file   the .toml case file
    /// @param[in] threads     worker threads, ≥ 1, held by a tbb::global_control for the lifetime
    ///                        of this object; none: TBB's default (all cores)
    /// @param[in] output_dir  where write_frame() and write_summary() write; empty: the case's
    ///                        simulation.output_dir (like `run --out`)
    /// @throws InputError for bad input, with the message `corocontact run` prints
    CaseRun(const std::filesystem::path& case_file, std::optional<Index> threads,
            const std::filesystem::path& output_dir);
    ~CaseRun();
    CaseRun(const CaseRun&) = delete;
    CaseRun& operator=(const CaseRun&) = delete;

    const CaseSpec& spec() const { return m_spec; }
    const Scene& scene() const { return m_loaded.scene; }
    /// What `corocontact run` prints as "warning: ..." (or as a note) while loading.
    const std::vector<std::string>& load_warnings() const { return m_load_warnings; }
    /// What the output calls had to say since the last call (a stale lock taken over, files of
    /// an earlier run removed), for the caller to pass on; cleared.
    std::vector<std::string> take_output_notes() { return std::exchange(m_output_notes, {}); }
    /// Worker threads TBB uses now (what summary.json reports).
    Index threads() const;

    /// Refuses n more steps before any is taken: after a divergence (NumericalError, its
    /// message), or beyond the last load step of a static analysis (InputError).
    void check_can_step(Index n) const;
    /// One time step or load step (Simulation::step).
    /// @throws NumericalError when the simulation diverges ("step N (t = ...): ..."); the
    ///         object then refuses step() and write_frame() (a half-taken step leaves no
    ///         meaningful state)
    /// @throws InputError for a static analysis whose load steps are all done
    void step();
    Index steps_done() const { return m_simulation->steps_done(); }
    double time() const { return m_simulation->time(); }

    /// The counters so far, with the time write_frame() took counted as `output` (the CLI counts
    /// its frames the same way).
    RunSummary summary() const;
    /// The summary as OUT/NAME.summary.json holds it (io/scene_output.hpp summary_json).
    std::string summary_json() const;
    /// Writes summary_json() to OUT/NAME.summary.json; returns the path.
    /// @throws OutputError as write_frame()
    std::filesystem::path write_summary();

    /// Writes the current state as frame `steps_done()` of the series OUT/NAME.pvd, exactly as
    /// `corocontact run` writes it (io/scene_output.hpp scene_frame, io/vtk_series.hpp). The
    /// first call of write_frame() or write_summary() takes the folder's lock, held as long as
    /// this object lives, and removes what an earlier run of the series left there, as
    /// `corocontact run` does before it writes.
    /// @return the .pvd path
    /// @throws InputError if this step's frame is already written
    /// @throws NumericalError after a divergence
    /// @throws OutputError if another run holds the folder, or a file cannot be written
    std::filesystem::path write_frame();
    /// OUT/NAME.pvd.
    std::filesystem::path series_path() const;

    // Inputs changed between steps. Each is checked like the case reader checks the case
    // file's values (InputError naming the body, node and value), then the contact response
    // the next step uses is recomputed with it, so the next step sees the change in full.

    /// @param[in] velocities  #V×3 [m/s], input node order; 0 on fixed nodes
    void set_velocities(Index body, CRef<Positions> velocities);
    /// @param[in] fixed  #V flags, input node order; nodes in no tet must stay fixed
    void set_fixed(Index body, const std::vector<char>& fixed);
    /// set_fixed()'s checks alone.
    void check_fixed(Index body, const std::vector<char>& fixed) const;
    /// @param[in] loads  #V×3 constant nodal forces [N], input node order
    void set_loads(Index body, CRef<Positions> loads);
    /// set_loads()'s checks alone.
    void check_loads(Index body, CRef<Positions> loads) const;
    /// The warning the scene loader gives for a body whose loads fall on fixed nodes (there they
    /// have no effect), or none: for its loads and fixed nodes, or for `loads` and `fixed`
    /// (input order) where given, to warn before a change is made.
    std::optional<std::string> loads_on_fixed_nodes(Index body, const Positions* loads = nullptr,
                                                    const std::vector<char>* fixed = nullptr) const;
    /// @param[in] gravity  [m/s²]
    void set_gravity(const Vec3& gravity);
    /// [contact] stiffness (> 0), damping (≥ 0), friction (in [0, MAX_FRICTION]).
    /// @throws InputError if the case has contact disabled
    void set_contact_stiffness(double stiffness);
    void set_contact_damping(double damping);
    void set_contact_friction(double friction);

private:
    Body& body(Index b);
    /// The load-time scale check (io/magnitudes.hpp) of every body, or of body b with
    /// `body_spec`, under `spec`; its InputError starts with `what` (the value being set), not
    /// with a line of the case file.
    void check_scales(const CaseSpec& spec, const char* what) const;
    void check_scales(const CaseSpec& spec, Index b, const BodySpec& body_spec, const std::string& what) const;
    void check_contact_applies(const char* key) const;
    /// The lock on the output folder and the series writer, made at the first write.
    VtkSeriesWriter& writer();

    std::unique_ptr<tbb::global_control> m_threads; // first: held while loading too
    CaseSpec m_spec;                                 // read by m_simulation
    LoadedScene m_loaded;                            // stepped by m_simulation
    std::unique_ptr<Simulation> m_simulation;
    std::vector<std::string> m_load_warnings;
    std::unique_ptr<OutputLock> m_lock;              // taken by the first write
    std::unique_ptr<VtkSeriesWriter> m_writer;       // made by the first write
    std::vector<std::string> m_output_notes;
    std::string m_diverged;                          // a step's NumericalError, or empty
    Index m_last_frame = -1;                         // step of the last frame written
    double m_output_s = 0.0;                         // time spent in write_frame() [s]
    double m_setup_s = 0.0;                          // reading and loading the case [s]
};

} // namespace coro::python
