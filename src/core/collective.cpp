#include <corocontact/core/collective.hpp>

#include <corocontact/core/error.hpp>

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

} // namespace coro
