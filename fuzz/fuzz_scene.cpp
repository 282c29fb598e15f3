// libFuzzer target: read_case + load_scene on a .toml case file whose bodies are built
// (a small cube.msh and cube.obj lie next to it for mesh bodies, surfaces and obstacles).
// InputError and NumericalError are expected answers; anything else is a finding.
#include "fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    coro::fuzz::feed(coro::fuzz::Target::SCENE, data, size);
    return 0;
}
