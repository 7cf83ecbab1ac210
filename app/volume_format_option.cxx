#include "volume_format_option.h"

#include "cli_options.h"

namespace repose {

std::string normalizedFormat(std::string ext) {
  if (!ext.empty() && ext[0] != '.') ext = "." + ext;
  for (const char* known : {".nii.gz", ".nii", ".nrrd", ".nhdr", ".mha", ".mhd", ".vti"})
    if (ext == known) return ext;
  throw UsageError("unknown image format '" + ext + "' (use .nii.gz, .nii, .nrrd, .nhdr, .mha, .mhd or .vti)");
}

std::string normalizedLabelFormat(std::string ext) {
  if (ext == "seg.nrrd" || ext == ".seg.nrrd") return ".seg.nrrd";
  try {
    return normalizedFormat(ext);
  } catch (const UsageError&) {
    throw UsageError("unknown label volume format '" + ext +
                     "' (use .nii.gz, .nii, .nrrd, .nhdr, .mha, .mhd, .vti or .seg.nrrd)");
  }
}

std::string imageFormatBeside(const std::string& labelsFormat) {
  return labelsFormat == ".seg.nrrd" ? ".nrrd" : labelsFormat;
}

bool isVdbFormat(const std::string& format) { return format == "vdb" || format == ".vdb"; }

}  // namespace repose
