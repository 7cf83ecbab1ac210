#pragma once
// Checks that a file an output writer produced is complete, down to its last byte, and on disk.
// Writers (ITK's NIfTI, VTK's XML, std::ofstream) can lose a short write on a full disk or past the
// process's file-size limit and still report success; these checks turn that into an error
// "PATH: cannot write (REASON)" naming the final file, never the temporary one.
#include <cstdint>
#include <stdexcept>
#include <string>

namespace repose {

/// Why writing `path` failed, when known: strerror(err) when the writer left a telling errno, else
/// what the file system says (no space left, the file-size limit reached); "" otherwise.
std::string knownWriteFailure(const std::string& path, int err);
/// True for the errors of the storage itself (no space, quota, file too large, I/O, read-only),
/// which an errno left by a library that failed for another reason rarely is.
bool isStorageError(int err);
/// knownWriteFailure, or "the file is incomplete".
std::string writeFailureReason(const std::string& path, int err);

/// "NAME: cannot write (REASON)"; `reason` alone for writers that word their own messages.
struct WriteFailure : std::runtime_error {
  WriteFailure(const std::string& name, const std::string& why)
      : std::runtime_error(name + ": cannot write (" + why + ")"), reason(why) {}
  std::string reason;
};

/// Throws WriteFailure, its reason from writeFailureReason(path, err).
[[noreturn]] void throwWriteFailure(const std::string& name, const std::string& path, int err = 0);

/// Flushes `path` to the disk (fsync) and requires at least `minBytes` in it; a folder is flushed
/// with everything inside. `name` is the file as the user knows it (for the message).
void requireWritten(const std::string& name, const std::string& path, std::uintmax_t minBytes = 1);

/// Flushes a folder's entries (the files moved into it) to the disk.
void syncFolder(const std::string& dir);

/// Requires the file to end with `tail` (a VTK XML file ends with "</VTKFile>\n").
void requireEndsWith(const std::string& name, const std::string& path, const std::string& tail);

/// Reads a gzip file to its end (each member's CRC and length checked) and requires at least
/// `minBytes` of decompressed content.
void requireCompleteGzip(const std::string& name, const std::string& path, std::uintmax_t minBytes);

}  // namespace repose
