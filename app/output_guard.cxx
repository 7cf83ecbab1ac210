#include "output_guard.h"

#include <filesystem>
#include <stdexcept>

namespace repose {
namespace fs = std::filesystem;

namespace {

fs::path canonicalOf(const fs::path& p) {
  std::error_code ec;
  fs::path c = fs::weakly_canonical(fs::absolute(p), ec);
  return ec ? fs::absolute(p).lexically_normal() : c;
}

/// `inner` equals `outer` or lies inside it (both canonical).
bool within(const fs::path& inner, const fs::path& outer) {
  auto i = inner.begin();
  for (auto o = outer.begin(); o != outer.end(); ++o, ++i)
    if (o->empty()) continue;  // a trailing separator
    else if (i == inner.end() || *i != *o) return false;
  return true;
}

bool sameFile(const fs::path& a, const fs::path& b) {
  std::error_code ec;
  return fs::exists(a, ec) && fs::exists(b, ec) && fs::equivalent(a, b, ec);
}

[[noreturn]] void refuse(const std::string& out, const std::string& what, const std::string& input) {
  throw std::runtime_error(out + ": --out " + what + " " + input + "; choose another --out");
}

}  // namespace

void refuseOutputsOverInputs(const std::string& outDir, const std::vector<std::string>& outputNames,
                             const CommandInputs& inputs) {
  const fs::path out = canonicalOf(outDir.empty() ? "." : outDir);
  std::error_code ec;
  for (const std::string& folder : inputs.folders) {
    if (folder.empty() || !fs::is_directory(folder, ec)) continue;
    const fs::path in = canonicalOf(folder);
    if (within(out, in)) refuse(outDir, out == in ? "is the input folder" : "lies inside the input folder", folder);
  }
  for (const std::string& file : inputs.files) {
    if (file.empty() || !fs::exists(file, ec)) continue;
    const fs::path in = canonicalOf(file);
    if (out == in || sameFile(outDir, file)) refuse(outDir, "is the input", file);
    for (const std::string& name : outputNames) {
      const fs::path target = fs::path(outDir.empty() ? "." : outDir) / name;
      // An output folder (frames/) is replaced whole: an input inside it would go with it.
      if (within(in, canonicalOf(target)) || sameFile(target, file)) refuse(target.string(), "would replace the input", file);
    }
  }
}

}  // namespace repose
