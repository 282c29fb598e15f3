// GoogleTest main for every suite: `--threads N` sets the TBB thread count, as in the
// corocontact command (the only other place that may set it).
#include <gtest/gtest.h>

#include <tbb/global_control.h>

#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>

int main(int argc, char** argv)
{
    ::testing::InitGoogleTest(&argc, argv);
    std::unique_ptr<tbb::global_control> threads;
    for (int i = 1; i + 1 < argc; ++i)
        if (std::strcmp(argv[i], "--threads") == 0)
            threads = std::make_unique<tbb::global_control>(
                tbb::global_control::max_allowed_parallelism,
                static_cast<std::size_t>(std::stoul(argv[i + 1])));
    return RUN_ALL_TESTS();
}
