#pragma once
// The options of one `repose` command: `--name value` (or `--name=value`), `--flag` and `-h`/`--help`.
#include <map>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace repose {

/// A command-line mistake: `repose` exits with code 2, as opposed to 1 for a bad input file.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// `--name value` options and `--flag` switches of one command, parsed from argv[first..argc).
/// Throws UsageError on an unknown option, a stray argument or a missing value.
class Options {
public:
  Options(int argc, char** argv, int first, const std::set<std::string>& valued, const std::set<std::string>& flags);
  bool has(const std::string& n) const { return values_.count(n) != 0; }
  std::string get(const std::string& n, const std::string& fallback = "") const;
  /// The value of an option that must be given (and not empty).
  std::string require(const std::string& n) const;
  /// The value as a finite number, or fallback when the option is absent.
  double number(const std::string& n, double fallback) const;
  /// Every value of a repeatable option, in order.
  std::vector<std::string> all(const std::string& n) const;
  bool help = false;

private:
  std::map<std::string, std::string> values_;
  std::map<std::string, std::vector<std::string>> lists_;
};

/// The files named by the options `names`, and every --mesh: the inputs no output may replace.
std::vector<std::string> inputFiles(const Options& o, const std::vector<std::string>& names);

}  // namespace repose
