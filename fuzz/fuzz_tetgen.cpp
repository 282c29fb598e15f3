// libFuzzer target: read_tet_mesh on x.ele + x.node (the input split at the line #--ele--).
// InputError and NumericalError are expected answers; anything else is a finding.
#include "fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    coro::fuzz::feed(coro::fuzz::Target::TETGEN, data, size);
    return 0;
}
