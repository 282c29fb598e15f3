#include <corocontact/io/output_file.hpp>

#include <corocontact/core/atomic_file.hpp>
#include <corocontact/core/error.hpp>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace coro {
namespace {

[[noreturn]] void fail(const std::filesystem::path& path, const char* what, int error)
{
    CORO_THROW(OutputError, path.string() << ": cannot " << what << " (" << std::strerror(error) << ")");
}

/// Opens what `path` is (following a symlink) and writes `bytes` to it; no fsync, which a pipe
/// or a device refuses.
void write_through(const std::filesystem::path& path, std::string_view bytes)
{
    const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0)
        fail(path, "open", errno);
    const char* data = bytes.data();
    std::size_t left = bytes.size();
    while (left > 0) {
        const ssize_t written = ::write(fd, data, left);
        if (written < 0 && errno == EINTR)
            continue;
        if (written < 0) {
            const int error = errno;
            ::close(fd);
            fail(path, "write", error);
        }
        data += written;
        left -= static_cast<std::size_t>(written);
    }
    if (::close(fd) != 0)
        fail(path, "write (close)", errno);
}

} // namespace

void write_output_file(const std::filesystem::path& path, std::string_view bytes)
{
    struct stat status {};
    if (::lstat(path.c_str(), &status) != 0 || S_ISREG(status.st_mode))
        write_file_atomically(path, bytes);
    else
        write_through(path, bytes);
}

} // namespace coro
