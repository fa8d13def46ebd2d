#pragma once
// File access with the guarantees the store relies on: whole-file reads, and
// atomic writes (temporary file in the same directory, fsync, rename), so a
// crash or a full disk never leaves a partial file under the final name.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "relief/base/result.h"

namespace relief {

// Reads a whole regular file of at most `max_bytes` (through symlinks). A FIFO,
// device, socket or directory is refused before anything is read (a FIFO
// would block, /dev/zero never end), and so is a larger file (a sparse
// terabyte is an error, not a read); a file that grows past `max_bytes` while
// it is read too. Every caller says how large its file can sensibly be.
Result<std::vector<std::byte>> read_file(const std::filesystem::path& path, uint64_t max_bytes);
// For a file whose size the caller already trusts (tests reading what they wrote).
inline constexpr uint64_t kNoSizeLimit = UINT64_MAX;
Result<std::string> read_text_file(const std::filesystem::path& path, uint64_t max_bytes);

// Whether `path` (through symlinks) is a regular file; otherwise a one-line
// error naming it and what it is ("is a FIFO, not a regular file"). For
// inputs handed to a library that opens them itself (GDAL).
Status check_regular_file(const std::filesystem::path& path);

// Whether a rename may replace `path`: it is absent, or a regular file (through
// symlinks). A device node, FIFO, socket or directory is refused with a one-line
// error, so no writer ever swaps /dev/null for a file or replaces a named pipe.
Status check_replaceable(const std::filesystem::path& path);

// Writes `bytes` to `path` atomically, creating parent directories. The rename
// makes the write atomic against a killed process; `durable` adds an fsync so it
// also survives a power cut (used for manifests, not for every tile). Refuses a
// `path` that check_replaceable refuses.
Status write_file_atomic(const std::filesystem::path& path, std::span<const std::byte> bytes,
                         bool durable = false);
Status write_text_file_atomic(const std::filesystem::path& path, std::string_view text,
                              bool durable = true);

// Temporary files left behind by a killed writer end with this marker plus a
// suffix that starts with the writer's process id: "<final>.tmp.<pid>[.<n>]".
inline constexpr std::string_view kTempMarker = ".tmp.";
bool is_temporary_file(const std::filesystem::path& path);
// A temporary name for `final_path` owned by this process.
std::string temporary_name(const std::filesystem::path& final_path);
// A temporary file (or directory) whose writing process is no longer running.
bool is_stale_temporary_file(const std::filesystem::path& path);
// Removes the stale temporaries of `final_path` (files or directories named
// "<final_path>.tmp.<pid>..." of dead processes) beside it; returns how many.
Result<uint64_t> remove_stale_temporaries_of(const std::filesystem::path& final_path);

// Human-readable description of errno for messages.
std::string errno_text(int err);

}  // namespace relief
