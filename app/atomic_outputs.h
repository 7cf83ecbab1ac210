#pragma once
// A command's outputs are first written into a hidden temporary folder inside their final folder
// and moved into place only when all of them are complete, so a failed run leaves no partial output.
#include <string>

namespace repose {

class AtomicOutputs {
public:
  /// Creates `finalDir` (and parents) and a temporary folder inside it.
  explicit AtomicOutputs(const std::string& finalDir);
  AtomicOutputs(const AtomicOutputs&) = delete;
  AtomicOutputs& operator=(const AtomicOutputs&) = delete;
  /// Removes the temporary folder and everything in it unless committed.
  ~AtomicOutputs();

  /// Where to write the output that will be called `name` in the final folder.
  std::string stage(const std::string& name) const;
  /// Moves every file of the temporary folder (companion files such as .raw included) into the
  /// final folder. Throws std::runtime_error on failure.
  void commit();
  const std::string& finalDir() const { return finalDir_; }

private:
  std::string finalDir_, tempDir_;
  bool committed_ = false;
};

/// Creates the directory and its parents; throws std::runtime_error naming it on failure.
void makeDirectories(const std::string& dir);
/// Reads a whole text file; throws std::runtime_error "PATH: cannot read (...)" on failure.
std::string readTextFile(const std::string& path);
void writeTextFile(const std::string& path, const std::string& text);
bool fileExists(const std::string& path);
/// "a/b/labels.nii.gz" -> ".nii.gz"; "" when there is none.
std::string imageExtension(const std::string& path);

}  // namespace repose
