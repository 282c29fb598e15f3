#include <corocontact/io/output_lock.hpp>

#include <corocontact/core/error.hpp>

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <climits>
#include <cstring>
#include <ctime>
#include <sstream>
#include <string>
#include <system_error>

namespace fs = std::filesystem;

namespace coro {
namespace {

constexpr const char* LOCK_FILE = "corocontact.lock";

/// "started" line of a lock file: the current time in UTC.
std::string now_utc()
{
    const std::time_t now = std::time(nullptr);
    std::tm utc{};
    gmtime_r(&now, &utc);
    std::array<char, 32> text{};
    std::strftime(text.data(), text.size(), "%Y-%m-%d %H:%M:%S UTC", &utc);
    return text.data();
}

std::string host_name()
{
    std::array<char, HOST_NAME_MAX + 1> name{};
    if (gethostname(name.data(), name.size() - 1) != 0)
        return "unknown";
    return name.data();
}

/// The whole file behind `fd`, from its start (a lock file is a few lines).
std::string read_all(int fd)
{
    std::string text;
    std::array<char, 512> buffer{};
    for (off_t at = 0;;) {
        const ssize_t n = pread(fd, buffer.data(), buffer.size(), at);
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0 || text.size() > 4096)
            break;
        text.append(buffer.data(), static_cast<std::size_t>(n));
        at += n;
    }
    return text;
}

/// "pid 4242 on host h, started 2026-11-26 10:00:00 UTC: corocontact run x.toml" from the
/// lines `pid`, `host`, `started`, `command` of a lock file.
std::string describe_owner(const std::string& text)
{
    std::string pid = "?", host = "?", started = "?", command;
    std::istringstream lines(text);
    for (std::string line; std::getline(lines, line);) {
        const std::size_t space = line.find(' ');
        if (space == std::string::npos)
            continue;
        const std::string key = line.substr(0, space), value = line.substr(space + 1);
        if (key == "pid")
            pid = value;
        else if (key == "host")
            host = value;
        else if (key == "started")
            started = value;
        else if (key == "command")
            command = value;
    }
    return "pid " + pid + " on host " + host + ", started " + started + (command.empty() ? "" : ": " + command);
}

[[noreturn]] void fail(const fs::path& path, const std::string& what, int error)
{
    CORO_THROW(OutputError, path.string() << ": " << what << " (" << std::strerror(error) << ")");
}

} // namespace

OutputLock::OutputLock(fs::path dir, const std::string& command) : m_dir(std::move(dir))
{
    std::error_code ec;
    // The folders this lock makes, deepest first: removed again if the run writes nothing.
    for (fs::path folder = m_dir.lexically_normal(); !folder.empty() && !fs::exists(folder, ec);
         folder = folder.parent_path()) {
        m_created.push_back(folder);
        if (folder == folder.parent_path())
            break;
    }
    fs::create_directories(m_dir, ec);
    if (ec || !fs::is_directory(m_dir))
        CORO_THROW(OutputError, m_dir.string() << ": cannot create the output folder ("
                                               << (ec ? ec.message() : std::string("a file of that name is in the way"))
                                               << ")");
    const fs::path file = path();
    // Another run may remove its lock file between our open and our flock: then we hold a lock
    // on a file that no longer has this name, and try again with the new one.
    for (int attempt = 0; attempt < 100; ++attempt) {
        const int fd = ::open(file.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
        if (fd < 0)
            fail(file, "cannot create the lock file of the output folder", errno);
        if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
            const int error = errno;
            const std::string owner = read_all(fd);
            ::close(fd);
            if (error == EWOULDBLOCK)
                CORO_THROW(OutputError, m_dir.string() << ": the output folder is in use by another run ("
                                                       << describe_owner(owner) << "; lock file " << file.string()
                                                       << "); wait for it to end or choose another --out");
            fail(file, "cannot lock the output folder", error);
        }
        struct stat held {}, named {};
        if (::fstat(fd, &held) != 0 || ::stat(file.c_str(), &named) != 0 || held.st_ino != named.st_ino ||
            held.st_dev != named.st_dev) {
            ::close(fd);
            continue;
        }
        m_fd = fd;
        break;
    }
    if (m_fd < 0)
        CORO_THROW(OutputError, file.string() << ": cannot lock the output folder (its lock file keeps changing)");

    const std::string left = read_all(m_fd);
    if (!left.empty())
        m_stale_owner = describe_owner(left);
    std::ostringstream text;
    text << "pid " << ::getpid() << "\nhost " << host_name() << "\nstarted " << now_utc() << "\ncommand " << command
         << "\n";
    const std::string bytes = text.str();
    if (::ftruncate(m_fd, 0) != 0 || ::pwrite(m_fd, bytes.data(), bytes.size(), 0) != static_cast<ssize_t>(bytes.size())) {
        const int error = errno;
        ::unlink(file.c_str());
        ::close(m_fd);
        remove_created_folders();
        fail(file, "cannot write the lock file of the output folder", error);
    }
}

OutputLock::~OutputLock()
{
    ::unlink(path().c_str());
    ::close(m_fd);
    remove_created_folders();
}

void OutputLock::remove_created_folders() const
{
    std::error_code ec;
    for (const fs::path& folder : m_created)
        if (!fs::remove(folder, ec)) // only an empty folder: never what a run wrote
            return;
}

fs::path OutputLock::path() const { return m_dir / LOCK_FILE; }

} // namespace coro
