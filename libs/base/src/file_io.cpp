#include "relief/base/file_io.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstring>

#include "relief/base/units.h"

namespace relief {
namespace fs = std::filesystem;

std::string errno_text(int err) {
  return std::strerror(err);
}

bool is_temporary_file(const fs::path& path) {
  return path.filename().string().find(kTempMarker) != std::string::npos;
}

namespace {

const char* file_type_name(mode_t mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

}  // namespace

Result<std::vector<std::byte>> read_file(const fs::path& path, uint64_t max_bytes) {
  // O_NONBLOCK: opening a FIFO without a writer returns at once (it is then
  // refused by its type) instead of waiting for one.
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) return fail(fmt::format("{}: cannot open: {}", path.string(), errno_text(errno)));
  struct stat st {};
  std::string error;
  if (::fstat(fd, &st) != 0) {
    error = fmt::format("{}: cannot stat: {}", path.string(), errno_text(errno));
  } else if (!S_ISREG(st.st_mode)) {
    error = fmt::format("{}: is {}, not a regular file", path.string(), file_type_name(st.st_mode));
  } else if (static_cast<uint64_t>(st.st_size) > max_bytes) {
    error = fmt::format("{}: {} bytes, more than {}, the most this file can hold", path.string(),
                        st.st_size, format_bytes(max_bytes));
  }
  std::vector<std::byte> bytes;
  if (error.empty()) bytes.reserve(static_cast<size_t>(st.st_size));
  while (error.empty()) {
    std::byte chunk[1 << 16];
    const ssize_t n = ::read(fd, chunk, sizeof chunk);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) error = fmt::format("{}: read failed: {}", path.string(), errno_text(errno));
    if (n <= 0) break;
    if (bytes.size() + static_cast<size_t>(n) > max_bytes) {  // it grew while being read
      error = fmt::format("{}: more than {}, the most this file can hold", path.string(),
                          format_bytes(max_bytes));
    }
    bytes.insert(bytes.end(), chunk, chunk + n);
  }
  ::close(fd);
  if (!error.empty()) return fail(error);
  return bytes;
}

Result<std::string> read_text_file(const fs::path& path, uint64_t max_bytes) {
  auto bytes = read_file(path, max_bytes);
  if (!bytes) return std::unexpected(bytes.error());
  return std::string(reinterpret_cast<const char*>(bytes->data()), bytes->size());
}

Status check_regular_file(const fs::path& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    return fail(fmt::format("{}: cannot open: {}", path.string(), errno_text(errno)));
  }
  if (S_ISREG(st.st_mode)) return {};
  return fail(
      fmt::format("{}: is {}, not a regular file", path.string(), file_type_name(st.st_mode)));
}

Status check_replaceable(const fs::path& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return {};  // absent (or a dangling symlink): created anew
  if (S_ISREG(st.st_mode)) return {};
  return fail(fmt::format("{}: is {}, not a regular file; refusing to replace it", path.string(),
                          file_type_name(st.st_mode)));
}

std::string temporary_name(const fs::path& path) {
  static std::atomic<unsigned> counter{0};
  return fmt::format("{}{}{}.{}", path.string(), kTempMarker, ::getpid(), counter.fetch_add(1));
}

bool is_stale_temporary_file(const fs::path& path) {
  const std::string name = path.filename().string();
  const size_t marker = name.rfind(kTempMarker);
  if (marker == std::string::npos) return false;
  const size_t start = marker + kTempMarker.size();
  const size_t end = std::min(name.find_first_not_of("0123456789", start), name.size());
  if (end == start || end - start > 9 || (end != name.size() && name[end] != '.')) {
    return false;  // no process id: not one of ours
  }
  const auto pid = static_cast<pid_t>(std::stol(name.substr(start, end - start)));
  if (pid <= 0 || pid == ::getpid()) return false;
  // EPERM: alive under another user. A reused id keeps a file; never a live one lost.
  return ::kill(pid, 0) != 0 && errno == ESRCH;
}

Result<uint64_t> remove_stale_temporaries_of(const fs::path& final_path) {
  const fs::path parent = final_path.has_parent_path() ? final_path.parent_path() : ".";
  const std::string prefix = final_path.filename().string() + std::string(kTempMarker);
  std::error_code ec;
  std::vector<fs::path> stale;
  for (auto it = fs::directory_iterator(parent, ec); !ec && it != fs::directory_iterator();
       it.increment(ec)) {
    const fs::path& p = it->path();
    if (p.filename().string().starts_with(prefix) && is_stale_temporary_file(p)) {
      stale.push_back(p);
    }
  }
  for (const auto& p : stale) {
    fs::remove_all(p, ec);
    if (ec) return fail(fmt::format("{}: cannot remove: {}", p.string(), ec.message()));
  }
  return stale.size();
}

namespace {

Status write_all(int fd, std::span<const std::byte> bytes, const std::string& name) {
  size_t done = 0;
  while (done < bytes.size()) {
    ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      return fail(fmt::format("{}: write failed: {}", name, errno_text(errno)));
    }
    done += static_cast<size_t>(n);
  }
  return {};
}

}  // namespace

Status write_file_atomic(const fs::path& path, std::span<const std::byte> bytes, bool durable) {
  RELIEF_CHECK(check_replaceable(path));
  std::error_code ec;
  if (path.has_parent_path()) {
    fs::create_directories(path.parent_path(), ec);
    if (ec) {
      return fail(fmt::format("{}: cannot create directory: {}", path.parent_path().string(),
                              ec.message()));
    }
  }
  const std::string tmp = temporary_name(path);
  int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd < 0) return fail(fmt::format("{}: cannot create: {}", path.string(), errno_text(errno)));
  auto status = write_all(fd, bytes, path.string());
  if (status && durable && ::fsync(fd) != 0 && errno != EINVAL) {
    status = fail(fmt::format("{}: fsync failed: {}", path.string(), errno_text(errno)));
  }
  if (::close(fd) != 0 && status) {
    status = fail(fmt::format("{}: close failed: {}", path.string(), errno_text(errno)));
  }
  // Checked again just before the rename: the target may have appeared meanwhile.
  if (status) status = check_replaceable(path);
  if (status && ::rename(tmp.c_str(), path.c_str()) != 0) {
    status = fail(fmt::format("{}: rename failed: {}", path.string(), errno_text(errno)));
  }
  if (!status) ::unlink(tmp.c_str());
  return status;
}

Status write_text_file_atomic(const fs::path& path, std::string_view text, bool durable) {
  return write_file_atomic(
      path, std::span(reinterpret_cast<const std::byte*>(text.data()), text.size()), durable);
}

}  // namespace relief
