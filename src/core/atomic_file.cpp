#include <corocontact/core/atomic_file.hpp>

#include <corocontact/core/error.hpp>

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <string>
#include <system_error>

namespace fs = std::filesystem;

namespace coro {
namespace {

/// An open file descriptor, closed when it goes out of scope.
class Descriptor {
public:
    explicit Descriptor(int fd) : m_fd(fd) {}
    Descriptor(const Descriptor&) = delete;
    Descriptor& operator=(const Descriptor&) = delete;
    ~Descriptor()
    {
        if (m_fd >= 0)
            ::close(m_fd);
    }
    int get() const { return m_fd; }
    /// Closes now and returns errno of a failed close (0 if it succeeded): NFS reports a
    /// failed write only there.
    int close()
    {
        const int result = ::close(m_fd);
        m_fd = -1;
        return result == 0 ? 0 : errno;
    }

private:
    int m_fd;
};

[[noreturn]] void fail(const fs::path& temporary, const fs::path& path, const char* what, int error)
{
    remove_temporary(temporary);
    CORO_THROW(OutputError, path.string() << ": cannot " << what << " (" << std::strerror(error) << ")");
}

} // namespace

fs::path temporary_path(const fs::path& path) { return fs::path(path).concat(".tmp"); }

void write_file_atomically(const fs::path& path, std::string_view bytes, Sync sync)
{
    const fs::path temporary = temporary_path(path);
    Descriptor fd(::open(temporary.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644));
    if (fd.get() < 0)
        CORO_THROW(OutputError, path.string() << ": cannot create " << temporary.filename().string() << " ("
                                              << std::strerror(errno) << ")");
    const char* data = bytes.data();
    std::size_t left = bytes.size();
    while (left > 0) {
        const ssize_t written = ::write(fd.get(), data, left);
        if (written < 0 && errno == EINTR)
            continue;
        if (written < 0)
            fail(temporary, path, "write", errno);
        data += written;
        left -= static_cast<std::size_t>(written);
    }
    if (sync == Sync::FILE && ::fsync(fd.get()) != 0)
        fail(temporary, path, "write (fsync)", errno);
    if (const int error = fd.close(); error != 0)
        fail(temporary, path, "write (close)", error);
    if (::rename(temporary.c_str(), path.c_str()) != 0)
        fail(temporary, path, ("rename " + temporary.filename().string() + " into place").c_str(), errno);
}

void commit_file(const fs::path& temporary, const fs::path& path)
{
    if (::rename(temporary.c_str(), path.c_str()) != 0)
        fail(temporary, path, ("rename " + temporary.filename().string() + " into place").c_str(), errno);
}

void remove_temporary(const fs::path& temporary) noexcept
{
    std::error_code ec;
    if (fs::is_regular_file(fs::symlink_status(temporary, ec)))
        fs::remove(temporary, ec);
}

} // namespace coro
