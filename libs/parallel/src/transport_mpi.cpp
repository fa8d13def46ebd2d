// Transport over MPI: the module librelief_parallel_mpi.so (transport.h).
#include <mpi.h>

#include <chrono>
#include <climits>
#include <cstdlib>
#include <memory>
#include <thread>
#include <type_traits>

#include <fmt/format.h>

#include "transport.h"

namespace relief::parallel {

namespace {

using Clock = std::chrono::steady_clock;

std::string mpi_error(int code) {
  char text[MPI_MAX_ERROR_STRING];
  int length = 0;
  MPI_Error_string(code, text, &length);
  return std::string(text, static_cast<size_t>(length));
}

// Polls `requests` until all are done or the deadline passes; on a timeout,
// `pending(i)` names what request i was waiting for.
template <class Name>
Status wait_all(std::vector<MPI_Request>& requests, double timeout, int rank, Name pending) {
  const auto deadline = Clock::now() + std::chrono::duration<double>(timeout);
  for (int polls = 0;; ++polls) {
    bool all = true;
    for (MPI_Request& r : requests) {
      if (r == MPI_REQUEST_NULL) continue;
      int done = 0;
      if (int e = MPI_Test(&r, &done, MPI_STATUS_IGNORE); e != MPI_SUCCESS) {
        return fail(fmt::format("rank {}: MPI: {}", rank, mpi_error(e)));
      }
      all = all && done;
    }
    if (all) return {};
    if (Clock::now() > deadline) {
      for (size_t i = 0; i < requests.size(); ++i) {
        if (requests[i] != MPI_REQUEST_NULL) {
          return fail(
              fmt::format("rank {}: {} within {} s (it died or hangs)", rank, pending(i), timeout));
        }
      }
    }
    // Waiting for peers that render: poll, but do not spin.
    if (polls > 100) std::this_thread::sleep_for(std::chrono::microseconds(500));
  }
}

Status check_size(size_t bytes) {
  if (bytes > static_cast<size_t>(INT_MAX)) {
    return fail(fmt::format("a message of {} bytes is larger than MPI's {} bytes", bytes, INT_MAX));
  }
  return {};
}

class MpiTransport final : public Transport {
 public:
  MpiTransport(int rank, int size) : rank_(rank), size_(size) {}
  ~MpiTransport() override {
    int finalised = 0;
    MPI_Finalized(&finalised);
    if (!finalised) MPI_Finalize();
  }

  int rank() const override { return rank_; }
  int size() const override { return size_; }

  Status broadcast(std::span<std::byte> bytes, int root, double timeout) override {
    RELIEF_CHECK(check_size(bytes.size()));
    std::vector<MPI_Request> request(1);
    if (int e = MPI_Ibcast(bytes.data(), static_cast<int>(bytes.size()), MPI_BYTE, root,
                           MPI_COMM_WORLD, &request[0]);
        e != MPI_SUCCESS) {
      return fail(fmt::format("rank {}: MPI broadcast: {}", rank_, mpi_error(e)));
    }
    return wait_all(request, timeout, rank_, [&](size_t) {
      return rank_ == root ? std::string("a rank did not receive the broadcast")
                           : fmt::format("nothing from rank {}", root);
    });
  }

  Status exchange(std::span<const Comm::Send> sends, std::span<const Comm::Receive> receives,
                  int tag, double timeout) override {
    std::vector<MPI_Request> requests(receives.size() + sends.size(), MPI_REQUEST_NULL);
    for (size_t i = 0; i < receives.size(); ++i) {
      const Comm::Receive& r = receives[i];
      RELIEF_CHECK(check_size(r.bytes.size()));
      if (int e = MPI_Irecv(r.bytes.data(), static_cast<int>(r.bytes.size()), MPI_BYTE, r.from, tag,
                            MPI_COMM_WORLD, &requests[i]);
          e != MPI_SUCCESS) {
        return fail(
            fmt::format("rank {}: MPI receive from rank {}: {}", rank_, r.from, mpi_error(e)));
      }
    }
    for (size_t i = 0; i < sends.size(); ++i) {
      const Comm::Send& s = sends[i];
      RELIEF_CHECK(check_size(s.bytes.size()));
      // MPI's send buffer is const since MPI 3.
      if (int e = MPI_Isend(s.bytes.data(), static_cast<int>(s.bytes.size()), MPI_BYTE, s.to, tag,
                            MPI_COMM_WORLD, &requests[receives.size() + i]);
          e != MPI_SUCCESS) {
        return fail(fmt::format("rank {}: MPI send to rank {}: {}", rank_, s.to, mpi_error(e)));
      }
    }
    return wait_all(requests, timeout, rank_, [&](size_t i) {
      return i < receives.size()
                 ? fmt::format("nothing from rank {}", receives[i].from)
                 : fmt::format("rank {} took nothing", sends[i - receives.size()].to);
    });
  }

  [[noreturn]] void abort(int code) override {
    MPI_Abort(MPI_COMM_WORLD, code);
    std::_Exit(code);  // MPI_Abort does not return; in case it does
  }

 private:
  int rank_ = 0, size_ = 1;
};

Result<std::unique_ptr<Transport>> open_mpi() {
  int initialised = 0;
  MPI_Initialized(&initialised);
  if (!initialised && MPI_Init(nullptr, nullptr) != MPI_SUCCESS) {
    return fail("MPI: cannot initialise (is this run under mpirun?)");
  }
  // Errors come back as values: a dead peer is reported, not fatal.
  MPI_Comm_set_errhandler(MPI_COMM_WORLD, MPI_ERRORS_RETURN);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  return std::make_unique<MpiTransport>(rank, size);
}

}  // namespace

}  // namespace relief::parallel

// Checked against the type Comm::init casts the symbol to.
extern "C"
    [[gnu::visibility("default")]] relief::Result<std::unique_ptr<relief::parallel::Transport>>
    relief_parallel_open_mpi() {
  return relief::parallel::open_mpi();
}
static_assert(std::is_same_v<decltype(&relief_parallel_open_mpi), relief::parallel::OpenTransport>);
