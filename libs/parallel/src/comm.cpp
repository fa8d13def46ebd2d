#include "relief/parallel/comm.h"

#include <dlfcn.h>

#include <cstdlib>
#include <filesystem>

#include <fmt/format.h>

#include "transport.h"

namespace relief::parallel {

namespace {

namespace fs = std::filesystem;

// Where the MPI module may be: $RELIEF_PARALLEL_MODULE, then beside an
// installed program (bin/../lib/relief/), then the build tree.
std::vector<fs::path> module_candidates() {
  std::vector<fs::path> paths;
  if (const char* env = std::getenv("RELIEF_PARALLEL_MODULE"); env && *env) {
    paths.emplace_back(env);
  }
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    paths.push_back(exe.parent_path().parent_path() / RELIEF_PARALLEL_MODULE_INSTALL_SUBDIR /
                    RELIEF_PARALLEL_MODULE_NAME);
  }
  paths.emplace_back(RELIEF_PARALLEL_MODULE_BUILD_PATH);
  return paths;
}

// The MPI module (transport.h says why it is one). Loaded once per process,
// as MPI initialises once; kept for the process's life.
Result<OpenTransport> load_transport() {
  std::string tried;
  for (const fs::path& path : module_candidates()) {
    std::error_code ec;
    if (!fs::exists(path, ec)) {
      tried += (tried.empty() ? "" : ", ") + path.string();
      continue;
    }
    // Global: OpenMPI's own plugins (dlopened by libopen-pal) may resolve
    // symbols of libmpi, which this module brings in.
    void* module = dlopen(path.c_str(), RTLD_NOW | RTLD_GLOBAL);
    if (!module) return fail(fmt::format("parallel: cannot load {}: {}", path.string(), dlerror()));
    auto open = reinterpret_cast<OpenTransport>(dlsym(module, kOpenTransportSymbol));
    if (!open)
      return fail(fmt::format("parallel: {} has no {}", path.string(), kOpenTransportSymbol));
    return open;
  }
  return fail("parallel: the MPI module is not installed (looked for " + tried + ")");
}

}  // namespace

Result<std::unique_ptr<Comm>> Comm::init(double timeout_seconds) {
  const OpenTransport open = RELIEF_TRY(load_transport());
  std::unique_ptr<Transport> transport = RELIEF_TRY(open());
  return std::unique_ptr<Comm>(new Comm(std::move(transport), timeout_seconds));
}

Comm::Comm(std::unique_ptr<Transport> transport, double timeout)
    : transport_(std::move(transport)),
      rank_(transport_->rank()),
      size_(transport_->size()),
      timeout_(timeout) {}

Comm::~Comm() = default;  // the transport finalises MPI

Status Comm::broadcast(std::span<std::byte> bytes, int root) {
  if (rank_ == root) bytes_sent_ += bytes.size() * static_cast<uint64_t>(size_ - 1);
  return transport_->broadcast(bytes, root, timeout_);
}

Status Comm::exchange(std::span<const Send> sends, std::span<const Receive> receives) {
  const int tag = tag_++ % 30000;
  for (const Send& s : sends) bytes_sent_ += s.bytes.size();
  return transport_->exchange(sends, receives, tag, timeout_);
}

void Comm::abort(int code) {
  transport_->abort(code);
  std::_Exit(code);  // the transport does not return; the compiler cannot know
}

}  // namespace relief::parallel
