#pragma once
// The messages under Comm. MPI lives in a module of its own
// (librelief_parallel_mpi.so, transport_mpi.cpp) that Comm::init loads: linked
// into relief, libmpi and its ~10 shared libraries would load with every
// command (`relief info` included), not only with --parallel. Private to
// libs/parallel.
#include <memory>
#include <span>

#include "relief/base/result.h"
#include "relief/parallel/comm.h"

namespace relief::parallel {

// Operations fail when a peer has not answered within `timeout` seconds;
// messages name the waiting rank and the peer.
class Transport {
 public:
  virtual ~Transport() = default;  // finalises MPI
  virtual int rank() const = 0;
  virtual int size() const = 0;
  virtual Status broadcast(std::span<std::byte> bytes, int root, double timeout) = 0;
  // Messages of one call share `tag`.
  virtual Status exchange(std::span<const Comm::Send> sends,
                          std::span<const Comm::Receive> receives, int tag, double timeout) = 0;
  [[noreturn]] virtual void abort(int code) = 0;
};

// Initialises MPI (a process started without mpirun is one rank of one).
using OpenTransport = Result<std::unique_ptr<Transport>> (*)();

// The module's one entry point (dlsym), of type OpenTransport.
inline constexpr const char* kOpenTransportSymbol = "relief_parallel_open_mpi";

}  // namespace relief::parallel
