#pragma once
// Outputs never replace inputs. Before any work, a command checks the files it will write into its
// output folder against the files and folders it reads, through symbolic links (canonical paths)
// and hard links (same inode). Refused: an output that is an input file, an output folder (such as
// frames/, replaced whole) that holds an input, and an output folder that is an input folder (a
// case) or lies inside one. Writing beside inputs in their folder stays allowed when none is replaced.
#include <string>
#include <vector>

namespace repose {

struct CommandInputs {
  std::vector<std::string> files;    ///< read files (empty strings and missing paths are skipped)
  std::vector<std::string> folders;  ///< read folders, such as a case
};

/// Throws std::runtime_error "OUT/NAME: --out would replace the input IN; choose another --out" (or
/// "OUT: --out is the input folder IN", "... lies inside the input folder IN") when writing `outputNames` into
/// `outDir` would replace or enter an input.
void refuseOutputsOverInputs(const std::string& outDir, const std::vector<std::string>& outputNames,
                             const CommandInputs& inputs);

}  // namespace repose
