#include "pvd_series.h"

#include <sstream>

namespace repose {

std::string pvdText(const std::vector<PvdEntry>& entries) {
  std::ostringstream x;
  x.precision(9);
  x << "<?xml version=\"1.0\"?>\n"
    << "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <Collection>\n";
  for (const auto& e : entries)
    x << "    <DataSet timestep=\"" << e.time << "\" group=\"\" part=\"" << e.part << "\" file=\"" << e.file
      << "\"/>\n";
  x << "  </Collection>\n</VTKFile>\n";
  return x.str();
}

}  // namespace repose
