#include <corocontact/core/error.hpp>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

using ::testing::EndsWith;
using ::testing::HasSubstr;
using ::testing::Not;

namespace {

std::string message_of_failed_check()
{
    try {
        CORO_CHECK(1 + 1 == 3, InputError, "case.toml:3: expected " << 3);
    } catch (const coro::InputError& error) {
        return error.what();
    }
    return "";
}

/// Restores the setting a test changed.
class SourceLocations : public ::testing::Test {
protected:
    void TearDown() override { coro::set_source_locations_shown(m_saved); }
    bool m_saved = coro::source_locations_shown();
};

} // namespace

TEST_F(SourceLocations, HiddenMessageIsTheInputLocationAndConditionOnly)
{
    coro::set_source_locations_shown(false);
    EXPECT_EQ(message_of_failed_check(), "case.toml:3: expected 3");
}

TEST_F(SourceLocations, ShownMessageEndsInThisFileAndLine)
{
    coro::set_source_locations_shown(true);
    const std::string message = message_of_failed_check();
    EXPECT_THAT(message, testing::StartsWith("case.toml:3: expected 3 [test_error.cpp:"));
    EXPECT_THAT(message, EndsWith("]"));
    EXPECT_THAT(message, Not(HasSubstr("/"))); // the file name only, not the build machine's path
}
