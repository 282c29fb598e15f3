// Part of every executable of an ASan build: LeakSanitizer's suppressions, the same however the
// executable is run (tools/test.sh --sanitize, plain ctest in build-asan/, mpirun, or by hand).
//
// PETSc (the AMG preconditioner) and OpenMPI (which PETSc initialises, and the distributed run)
// keep allocations to the end of the process by design: their initialisation, MPI operator
// tables, and the plugins they open. Those libraries are not instrumented and not ours; a leak
// with one of them on its stack is theirs. Leaks in our code still fail their test.
extern "C" __attribute__((visibility("default"))) const char* __lsan_default_suppressions()
{
    return "leak:libpetsc\n"
           "leak:libmpi\n"
           "leak:libopen-pal\n"
           "leak:libopen-rte\n"
           "leak:libhwloc\n"
           "leak:libevent\n"
           "leak:libpmix\n"
           "leak:mca_\n";
}
