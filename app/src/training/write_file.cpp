// Whole-or-nothing file writes.
#include "sulcus/app/write_file.h"

#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <unistd.h>

namespace sulcus {

std::string write_file_atomic(const std::string& path, const std::string& text) {
    auto fail = [&](const std::string& what) { return path + ": " + what; };
    const std::string tmp = path + ".tmp." + std::to_string(::getpid());
    const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0) return fail(std::string("cannot create ") + tmp + " (" + std::strerror(errno) + ")");
    size_t done = 0;
    while (done < text.size()) {
        const ssize_t w = ::write(fd, text.data() + done, text.size() - done);
        if (w < 0 && errno == EINTR) continue;
        if (w <= 0) {
            const int e = errno;
            ::close(fd);
            ::unlink(tmp.c_str());
            return fail(std::string("write failed (") + std::strerror(e) + ")");
        }
        done += static_cast<size_t>(w);
    }
    // On disk before the rename, so that a crash leaves the old file or the whole new one.
    const int synced = ::fsync(fd);
    const int sync_errno = errno;
    if (::close(fd) != 0 || synced != 0) {
        const int e = synced != 0 ? sync_errno : errno;
        ::unlink(tmp.c_str());
        return fail(std::string("write failed (") + std::strerror(e) + ")");
    }
    if (::rename(tmp.c_str(), path.c_str()) != 0) {
        const int e = errno;
        ::unlink(tmp.c_str());
        return fail(std::string("cannot rename the temporary file into place (") + std::strerror(e) + ")");
    }
    return "";
}

}  // namespace sulcus
