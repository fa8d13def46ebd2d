#pragma once
// The ranks of a parallel render and the messages between them, over MPI
// (the only user of MPI; this header names no MPI type). Every operation is
// nonblocking underneath and polled against a deadline: a rank that died or
// hangs makes the operation fail with a message naming it, within the
// timeout, instead of blocking forever (MPI's errors are returned, not fatal).
// MPI itself is in a module loaded by init(), so a program that links this
// library loads libmpi only when it makes a Comm.
//
// One Comm per process, used from one thread.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "relief/base/result.h"

namespace relief::parallel {

class Transport;  // src/transport.h

class Comm {
 public:
  // Loads the MPI module and initialises MPI (a process started without
  // mpirun is one rank of one).
  // Operations fail when a peer has not answered within `timeout_seconds`.
  static Result<std::unique_ptr<Comm>> init(double timeout_seconds);
  ~Comm();  // finalises MPI (MPI cannot be initialised again in this process)
  Comm(const Comm&) = delete;
  Comm& operator=(const Comm&) = delete;

  int rank() const { return rank_; }
  int size() const { return size_; }
  double timeout_seconds() const { return timeout_; }

  // Root's bytes into every rank's `bytes` (all ranks pass the same size).
  Status broadcast(std::span<std::byte> bytes, int root);

  struct Send {
    int to;
    std::span<const std::byte> bytes;
  };
  struct Receive {
    int from;
    std::span<std::byte> bytes;  // exactly this many bytes are expected
  };
  // All the sends and receives at once, done when every one is. Messages
  // between two ranks match in the order they are posted (one tag per call).
  Status exchange(std::span<const Send> sends, std::span<const Receive> receives);

  // Payload bytes this rank has sent so far (broadcasts count at the root).
  uint64_t bytes_sent() const { return bytes_sent_; }

  // Ends every rank of the run with `code` (after a failure on this rank:
  // the others may be waiting for it).
  [[noreturn]] void abort(int code);

 private:
  Comm(std::unique_ptr<Transport> transport, double timeout);
  std::unique_ptr<Transport> transport_;  // MPI, behind the module's interface
  int rank_ = 0, size_ = 1;
  double timeout_ = 60;
  int tag_ = 0;
  uint64_t bytes_sent_ = 0;
};

// Bytes of a trivially copyable value, for messages.
template <class T>
std::span<std::byte> bytes_of(T& value) {
  return std::as_writable_bytes(std::span<T, 1>(&value, 1));
}

}  // namespace relief::parallel
