// libFuzzer target: read_tet_mesh on a .msh file (Gmsh 2.2 / 4.1, ASCII and binary).
// InputError and NumericalError are expected answers; anything else is a finding.
#include "fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    coro::fuzz::feed(coro::fuzz::Target::MSH, data, size);
    return 0;
}
