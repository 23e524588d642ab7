#include <cdp/core/errors.h>
#include <cdp/io/atomic_write.h>

#include <cerrno>
#include <csignal>
#include <cstring>
#include <stdexcept>
#include <string>

#include <fcntl.h>
#include <unistd.h>

namespace cdp {

namespace {

// The temporary file being written, as a fixed buffer a signal handler may read: a
// std::string could be mid-reallocation when the signal arrives. Paths longer than this are
// refused by the kernel anyway (PATH_MAX).
constexpr std::size_t kMaxPath = 4096;
char g_pending[kMaxPath];
volatile std::sig_atomic_t g_has_pending = 0;

// Clears the registration when the write ends, however it ends.
struct PendingTemporary {
  explicit PendingTemporary(const std::string& path) {
    if (path.size() < kMaxPath) {
      std::memcpy(g_pending, path.c_str(), path.size() + 1);
      g_has_pending = 1;
    }
  }
  ~PendingTemporary() { g_has_pending = 0; }
};

std::string errno_text(int err) { return std::strerror(err); }

}  // namespace

void remove_pending_temporary_file() noexcept {
  if (g_has_pending) unlink(g_pending);
}

void write_file_atomically(const std::filesystem::path& path, std::string_view contents, std::string_view what) {
  write_file_atomically(path, [&](const ByteSink& append) { append(contents); }, what);
}

void write_file_atomically(const std::filesystem::path& path, const std::function<void(const ByteSink& append)>& produce,
                           std::string_view what) {
  const std::string failure = path.string() + ": cannot write" + (what.empty() ? "" : " " + std::string(what));
  std::filesystem::path tmp = path;
  // Hidden and per process, so that concurrent writers of one target never share a temporary.
  tmp.replace_filename("." + path.filename().string() + ".tmp" + std::to_string(getpid()));
  const std::string tmp_name = tmp.string();
  PendingTemporary pending(tmp_name);
  // Everything that may allocate is made before the file is opened: from the open to the end,
  // only fail and the producer throw, and both leave no temporary behind.
  int fd = -1;
  bool open_yet = false;  // true from the open until fail or the producer's error closes it
  const auto fail = [&](int err) {
    open_yet = false;
    close(fd);
    unlink(tmp_name.c_str());
    throw FileError(failure + ": " + errno_text(err), err);
  };
  const ByteSink append = [&](std::string_view contents) {
    if (!open_yet) throw std::logic_error("write_file_atomically: a piece appended after a failure");
    const char* data = contents.data();
    std::size_t left = contents.size();
    while (left > 0) {  // bounded: every pass writes at least one byte or fails
      const ssize_t n = write(fd, data, left);
      if (n < 0) {
        if (errno == EINTR) continue;
        fail(errno);
      }
      if (n == 0) fail(EIO);
      data += n;
      left -= static_cast<std::size_t>(n);
    }
  };
  // POSIX calls rather than a stream, so that the reason of a failure (a full disk, a file size
  // limit) reaches the message, and so that fsync can make the contents durable before the
  // rename makes them visible.
  fd = open(tmp_name.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) {
    const int err = errno;
    throw FileError(failure + ": " + errno_text(err), err);
  }
  open_yet = true;
  try {
    produce(append);
  } catch (...) {
    if (open_yet) {
      close(fd);
      unlink(tmp_name.c_str());
    }
    throw;
  }
  // A producer that caught a failed write's FileError and went on: the temporary is gone.
  if (!open_yet) throw std::logic_error("write_file_atomically: the producer went on after a failed write");
  if (fsync(fd) != 0) fail(errno);
  if (close(fd) != 0) {
    const int err = errno;
    unlink(tmp_name.c_str());
    throw FileError(failure + ": " + errno_text(err), err);
  }
  if (std::rename(tmp_name.c_str(), path.c_str()) != 0) {
    const int err = errno;
    unlink(tmp_name.c_str());
    throw FileError(failure + ": " + errno_text(err), err);
  }
}

}  // namespace cdp
