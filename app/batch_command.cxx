#include "batch_command.h"

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <system_error>
#include <unistd.h>
#include <vector>

#include "repose_version.h"

namespace repose {

void execBatchRunner(int argc, char** argv, int first) {
  namespace fs = std::filesystem;
  std::error_code error;
  const fs::path exe = fs::canonical("/proc/self/exe", error);
  if (error) throw std::runtime_error("cannot find the repose executable (" + error.message() + ")");
  // The package sits at the same place relative to bin/ in the build tree and in an installation.
  const fs::path package = fs::weakly_canonical(exe.parent_path() / REPOSE_PYTHON_PACKAGE_DIR);
  if (!fs::exists(package / "repose" / "batch" / "__main__.py"))
    throw std::runtime_error(package.string() + ": the batch runner (repose/batch) is not installed there");
  const char* oldPath = std::getenv("PYTHONPATH");
  const std::string pythonPath = package.string() + (oldPath && *oldPath ? ":" + std::string(oldPath) : "");
  setenv("PYTHONPATH", pythonPath.c_str(), 1);
  setenv("REPOSE_EXECUTABLE", exe.c_str(), 1);  // prepare runs `repose prepare`; workers need the same build
  setenv("REPOSE_VERSION", REPOSE_VERSION, 1);
  const char* python = std::getenv("REPOSE_PYTHON");
  if (!python || !*python) python = REPOSE_PYTHON_EXECUTABLE;
  std::vector<char*> args = {const_cast<char*>(python), const_cast<char*>("-m"), const_cast<char*>("repose.batch")};
  for (int i = first; i < argc; ++i) args.push_back(argv[i]);
  args.push_back(nullptr);
  execv(python, args.data());
  throw std::runtime_error(std::string(python) + ": cannot start the batch runner (" + std::strerror(errno) + ")");
}

}  // namespace repose
