#include "cli_options.h"

#include <cmath>
#include <cstdlib>

namespace repose {

Options::Options(int argc, char** argv, int first, const std::set<std::string>& valued,
                 const std::set<std::string>& flags) {
  for (int i = first; i < argc; ++i) {
    std::string a = argv[i];
    if (a == "-h" || a == "--help") {
      help = true;
      continue;
    }
    if (a.rfind("--", 0) != 0) throw UsageError("unexpected argument '" + a + "'");
    std::string name = a.substr(2), value;
    const auto eq = name.find('=');
    if (eq != std::string::npos) {
      value = name.substr(eq + 1);
      name = name.substr(0, eq);
    }
    if (flags.count(name)) {
      values_[name] = "1";
    } else if (valued.count(name)) {
      if (eq == std::string::npos) {
        if (i + 1 >= argc) throw UsageError("option --" + name + " needs a value");
        value = argv[++i];
      }
      values_[name] = value;
      lists_[name].push_back(value);
    } else {
      throw UsageError("unknown option --" + name);
    }
  }
}

std::string Options::get(const std::string& n, const std::string& fallback) const {
  auto it = values_.find(n);
  return it == values_.end() ? fallback : it->second;
}

std::string Options::require(const std::string& n) const {
  if (!has(n) || get(n).empty()) throw UsageError("missing required option --" + n);
  return get(n);
}

double Options::number(const std::string& n, double fallback) const {
  if (!has(n)) return fallback;
  char* end = nullptr;
  const std::string v = get(n);
  const double x = std::strtod(v.c_str(), &end);
  if (v.empty() || *end != '\0' || !std::isfinite(x)) throw UsageError("--" + n + " needs a number, not '" + v + "'");
  return x;
}

std::vector<std::string> Options::all(const std::string& n) const {
  auto it = lists_.find(n);
  return it == lists_.end() ? std::vector<std::string>() : it->second;
}

std::vector<std::string> inputFiles(const Options& o, const std::vector<std::string>& names) {
  std::vector<std::string> files = o.all("mesh");
  for (const std::string& n : names) files.push_back(o.get(n));
  return files;
}

}  // namespace repose
