#pragma once
// `repose voxelize`: surface meshes (skin, bones, other tissues) -> one label volume and its table.

namespace repose {

extern const char* kVoxelizeUsage;

/// Runs `repose voxelize` on argv[first..argc); returns the exit code. Throws UsageError on
/// bad options and std::exception ("FILE: problem") on bad input; nothing is written then.
int runVoxelizeCommand(int argc, char** argv, int first);

}  // namespace repose
