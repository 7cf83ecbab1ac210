#pragma once
// A command's outputs are first written into a hidden temporary folder inside their final folder
// and moved into place only when all of them are complete, so a failed run leaves no partial output.
// The temporary folder is named .repose-tmp-<pid> and locked (flock) while its process lives: a
// later run in the same folder removes the folders whose lock is free (their process is dead, whatever
// process has its pid now), and an interrupted run's signal handler removes its own
// (removeTemporaryFolders).
#include <memory>
#include <string>
#include <vector>

namespace repose {

class AtomicOutputs {
public:
  /// Creates `finalDir` (and parents), removes stale temporary folders of dead processes in it and
  /// creates this run's temporary folder.
  explicit AtomicOutputs(const std::string& finalDir);
  AtomicOutputs(const AtomicOutputs&) = delete;
  AtomicOutputs& operator=(const AtomicOutputs&) = delete;
  /// Removes the temporary folder and everything in it and, unless committed, the folders the
  /// constructor created when they are empty.
  ~AtomicOutputs();

  /// Where to write the output that will be called `name` in the final folder.
  std::string stage(const std::string& name) const;
  /// Checks every staged file (flushed to the disk, not empty), then moves each (companion files
  /// such as .raw included) into the final folder. Throws std::runtime_error naming the final file.
  void commit();
  const std::string& finalDir() const { return finalDir_; }

private:
  std::string finalDir_, tempDir_;
  std::string createdRoot_;  // the outermost folder this run created ("" when finalDir existed)
  bool committed_ = false;
  std::unique_ptr<class TemporaryLock> lock_;  // held while this run writes
};

/// Removes the temporary folders of every AtomicOutputs alive in this process; safe to call from a
/// thread other than the writers' (a signal-handling thread). Returns their final folders.
std::vector<std::string> removeTemporaryFolders();
/// Removes the .repose-tmp-<pid>* entries of `dir` of other processes whose lock is free (their
/// writer is dead); returns how many.
int removeStaleTemporaryFolders(const std::string& dir);
/// A message with the temporary folders taken out of its paths, so it names the final files.
std::string withFinalPaths(std::string message);

/// Creates the directory and its parents; throws std::runtime_error naming it on failure.
void makeDirectories(const std::string& dir);
/// Reads a whole text file; throws std::runtime_error "PATH: cannot read (...)" on failure.
std::string readTextFile(const std::string& path);
/// Writes the text and checks it reached the file whole; throws "PATH: cannot write (REASON)".
void writeTextFile(const std::string& path, const std::string& text);
bool fileExists(const std::string& path);
/// "a/b/labels.nii.gz" -> ".nii.gz"; "" when there is none; "/" for a folder (a DICOM series).
std::string imageExtension(const std::string& path);

}  // namespace repose
