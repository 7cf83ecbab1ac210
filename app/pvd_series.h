#pragma once
// ParaView's time-series collection file (.pvd): one entry per time step and part.
#include <string>
#include <vector>

namespace repose {

struct PvdEntry {
  double time;
  int part;               ///< several parts at one time step open as one multiblock
  std::string file;       ///< relative to the .pvd
};

/// The .pvd XML text for `entries`.
std::string pvdText(const std::vector<PvdEntry>& entries);

}  // namespace repose
