#pragma once
// Writing a file so that no reader ever sees part of it and no failure leaves a trace.
#include <cstdint>
#include <string>
#include <string_view>

namespace pbnbv {

// Writes `bytes` to `path` through `path`.tmp renamed over it: a reader (or a process restarted
// after a crash) sees the old file or the new one, never a part. On any failure (a full disk, a
// read-only folder, a missing one) the .tmp is removed, `path` is left as it was, and
// std::runtime_error says "cannot write PATH: <the system's reason>" (e.g. "No space left on
// device").
void write_file_atomic(const std::string& path, std::string_view bytes);

// Whether `what` (an exception's message) says that a disk was full.
bool says_disk_full(std::string_view what);

// Bytes an unprivileged writer may still write on the file system holding `path` (statvfs), or -1
// when it cannot be asked.
int64_t free_bytes(const std::string& path);

// Space held back so that a last record can be written when the disk fills: a file of `bytes`
// zeros at `path`, written at once; release() (or the destructor) deletes it, freeing the space
// for that record. Throws std::runtime_error as write_file_atomic does when it cannot be written.
class SpaceReserve {
 public:
  SpaceReserve(std::string path, std::size_t bytes);
  ~SpaceReserve() { release(); }
  SpaceReserve(const SpaceReserve&) = delete;
  SpaceReserve& operator=(const SpaceReserve&) = delete;
  void release();

 private:
  std::string path_;
};

}  // namespace pbnbv
