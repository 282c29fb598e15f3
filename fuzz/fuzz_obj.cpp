// libFuzzer target: read_surface on a .obj file.
// InputError and NumericalError are expected answers; anything else is a finding.
#include "fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    coro::fuzz::feed(coro::fuzz::Target::OBJ, data, size);
    return 0;
}
