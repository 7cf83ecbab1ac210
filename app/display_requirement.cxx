#include "display_requirement.h"

#include <cstdlib>
#include <iostream>
#include <stdexcept>
#include <string>
#include <unistd.h>
#include <vector>

namespace repose {
namespace {

/// Replaces this process by `xvfb-run -a ARGV...`; returns only when that cannot be done.
bool reexecUnderXvfb(int argc, char** argv) {
  if (std::getenv("DISPLAY") || std::getenv("REPOSE_UNDER_XVFB")) return false;
  if (std::system("command -v xvfb-run >/dev/null 2>&1") != 0) return false;
  setenv("REPOSE_UNDER_XVFB", "1", 1);  // the child must not try again
  std::vector<char*> args;
  args.push_back(const_cast<char*>("xvfb-run"));
  args.push_back(const_cast<char*>("-a"));
  for (int i = 0; i < argc; ++i) args.push_back(argv[i]);
  args.push_back(nullptr);
  std::cout.flush();
  execvp("xvfb-run", args.data());
  return false;
}

}  // namespace

void requireDisplay(int argc, char** argv, const char* why) {
  if (std::getenv("DISPLAY") || std::getenv("REPOSE_UNDER_XVFB")) return;
  reexecUnderXvfb(argc, argv);
  throw std::runtime_error(std::string(why) + " needs an X display: install xvfb (xvfb-run)");
}

}  // namespace repose
