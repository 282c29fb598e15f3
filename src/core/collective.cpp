#include <corocontact/core/collective.hpp>

#include <corocontact/core/error.hpp>

#include <cstring>
#include <exception>
#include <string>
#include <vector>

namespace coro {

namespace {
enum class Kind : char { INPUT = 'I', OUTPUT = 'W', NUMERICAL = 'N', OTHER = 'O' };
} // namespace

void run_collectively(Communicator* communicator, FunctionRef<void()> work)
{
    if (communicator == nullptr) {
        work();
        return;
    }
    std::exception_ptr failure;
    std::vector<char> report; // kind, then the message
    try {
        work();
    } catch (const InputError& error) {
        failure = std::current_exception();
        report.push_back(static_cast<char>(Kind::INPUT));
        report.insert(report.end(), error.what(), error.what() + std::char_traits<char>::length(error.what()));
    } catch (const OutputError& error) {
        failure = std::current_exception();
        report.push_back(static_cast<char>(Kind::OUTPUT));
        report.insert(report.end(), error.what(), error.what() + std::char_traits<char>::length(error.what()));
    } catch (const NumericalError& error) {
        failure = std::current_exception();
        report.push_back(static_cast<char>(Kind::NUMERICAL));
        report.insert(report.end(), error.what(), error.what() + std::char_traits<char>::length(error.what()));
    } catch (const std::exception& error) {
        failure = std::current_exception();
        report.push_back(static_cast<char>(Kind::OTHER));
        report.insert(report.end(), error.what(), error.what() + std::char_traits<char>::length(error.what()));
    }
    std::int64_t first = failure ? communicator->rank() : communicator->size();
    communicator->all_reduce(&first, 1, Reduction::MIN);
    if (first == communicator->size())
        return;
    communicator->broadcast(report, static_cast<int>(first));
    if (communicator->rank() == first)
        std::rethrow_exception(failure);
    const std::string message(report.begin() + 1, report.end());
    switch (static_cast<Kind>(report.front())) {
    case Kind::INPUT: throw InputError(message);
    case Kind::OUTPUT: throw OutputError(message);
    case Kind::NUMERICAL: throw NumericalError(message);
    case Kind::OTHER: break;
    }
    throw std::runtime_error(message);
}

void require_same_on_every_process(Communicator* communicator, std::uint64_t fingerprint, const std::string& message)
{
    if (communicator == nullptr)
        return;
    std::int64_t lowest, highest;
    std::memcpy(&lowest, &fingerprint, sizeof lowest);
    highest = lowest;
    communicator->all_reduce(&lowest, 1, Reduction::MIN);
    communicator->all_reduce(&highest, 1, Reduction::MAX);
    CORO_CHECK(lowest == highest, InputError, message);
}

} // namespace coro
