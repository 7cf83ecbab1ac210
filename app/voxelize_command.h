#pragma once
// `repose voxelize`: surface meshes (skin, bones, other tissues) -> one label volume and its table.
#include <stdexcept>

namespace repose {

/// A command-line mistake (exit code 2), as opposed to a bad input file (exit code 1).
struct VoxelizeUsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

extern const char* kVoxelizeUsage;

/// Runs `repose voxelize` on argv[first..argc); returns the exit code. Throws VoxelizeUsageError on
/// bad options and std::exception ("FILE: problem") on bad input; nothing is written then.
int runVoxelizeCommand(int argc, char** argv, int first);

}  // namespace repose
