#include "relief/parallel/comm.h"

#include "relief/base/module.h"
#include "transport.h"

namespace relief::parallel {

namespace {

// The MPI module (transport.h says why it is one). Loaded once per process,
// as MPI initialises once. Global: OpenMPI's own plugins (dlopened by
// libopen-pal) may resolve symbols of libmpi, which this module brings in.
Result<OpenTransport> load_transport() {
  const ModuleLocation location{.what = "parallel",
                                .description = "MPI module",
                                .env_variable = "RELIEF_PARALLEL_MODULE",
                                .build_path = RELIEF_PARALLEL_MODULE_BUILD_PATH};
  void* open = RELIEF_TRY(load_module_symbol(location, kOpenTransportSymbol, SymbolScope::global));
  return reinterpret_cast<OpenTransport>(open);
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
