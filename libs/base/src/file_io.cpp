#include "relief/base/file_io.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <fmt/format.h>
#include <atomic>
#include <cerrno>
#include <cstring>

namespace relief {
namespace fs = std::filesystem;

std::string errno_text(int err) {
  return std::strerror(err);
}

Result<std::vector<std::byte>> read_file(const fs::path& path) {
  int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return fail(fmt::format("{}: cannot open: {}", path.string(), errno_text(errno)));
  std::vector<std::byte> bytes;
  std::byte chunk[1 << 16];
  for (;;) {
    ssize_t n = ::read(fd, chunk, sizeof chunk);
    if (n < 0) {
      if (errno == EINTR) continue;
      int err = errno;
      ::close(fd);
      return fail(fmt::format("{}: read failed: {}", path.string(), errno_text(err)));
    }
    if (n == 0) break;
    bytes.insert(bytes.end(), chunk, chunk + n);
  }
  ::close(fd);
  return bytes;
}

Result<std::string> read_text_file(const fs::path& path) {
  auto bytes = read_file(path);
  if (!bytes) return std::unexpected(bytes.error());
  return std::string(reinterpret_cast<const char*>(bytes->data()), bytes->size());
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

Status check_replaceable(const fs::path& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return {};  // absent (or a dangling symlink): created anew
  if (S_ISREG(st.st_mode)) return {};
  return fail(fmt::format("{}: is {}, not a regular file; refusing to replace it", path.string(),
                          file_type_name(st.st_mode)));
}

namespace {

std::string temp_name(const fs::path& path) {
  static std::atomic<unsigned> counter{0};
  return fmt::format("{}{}{}.{}", path.string(), kTempMarker, ::getpid(), counter.fetch_add(1));
}

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
  const std::string tmp = temp_name(path);
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
