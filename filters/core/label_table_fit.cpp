#include "label_table_fit.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>

#include "anatomy_names.h"

namespace repose {

std::string LabelTableFit::problem() const {
  std::ostringstream s;
  s << misplaced << " of " << checked << " bone labels lie where their names cannot be";
  for (std::size_t i = 0; i < examples.size() && i < 3; ++i) s << (i ? "; " : ": ") << examples[i];
  if (examples.size() > 3) s << "; ...";
  return s.str();
}

LabelTableFit checkLabelTableFit(const LabelVolume& labels, const LabelTable& table) {
  const ImageGrid& g = labels.grid;
  struct Sum {
    double x = 0;
    std::size_t n = 0;
  };
  std::map<int, Sum> perLabel;
  double xlo = 1e300, xhi = -1e300, xsum = 0;
  std::size_t count = 0;
  // x of a voxel: origin + direction row 0 . (spacing * index), accumulated per row of voxels.
  for (int k = 0; k < g.dims[2]; ++k)
    for (int j = 0; j < g.dims[1]; ++j) {
      const std::size_t row = g.linearIndex(0, j, k);
      const Eigen::Vector3d x0 = g.indexToPhysical(Eigen::Vector3d(0, j, k));
      const double dx = g.direction(0, 0) * g.spacing.x();
      for (int i = 0; i < g.dims[0]; ++i) {
        const int v = labels.data[row + i];
        if (v <= 0) continue;
        const double x = x0.x() + dx * i;
        Sum& s = perLabel[v];
        s.x += x;
        ++s.n;
        xsum += x;
        ++count;
        xlo = std::min(xlo, x);
        xhi = std::max(xhi, x);
      }
    }
  LabelTableFit fit;
  if (count == 0) return fit;
  const double mid = xsum / double(count);
  const double midlineTolerance = std::max(40.0, 0.15 * 0.5 * (xhi - xlo));
  for (const auto& [value, s] : perLabel) {
    const LabelInfo* info = table.find(value);
    if (!info || info->kind != LabelKind::Bone) continue;
    ++fit.boneLabels;
    const BoneName b = recogniseBone(info->name);
    const double dx = s.x / double(s.n) - mid;  // > 0: the patient's left
    std::ostringstream e;
    e.setf(std::ios::fixed);
    e.precision(0);
    e << info->name << " (" << value << ") lies " << std::abs(dx) << " mm " << (dx > 0 ? "left" : "right");
    bool misplaced = false;
    if (isMidlineBone(b.type)) {
      ++fit.checked;
      misplaced = std::abs(dx) > midlineTolerance;
      e << " of the midline";
    } else if (b.side != BoneSide::None) {
      ++fit.checked;
      misplaced = (b.side == BoneSide::Left ? dx : -dx) < -20.0;
      e << " of the midline, on the other side";
    }
    if (misplaced) {
      ++fit.misplaced;
      fit.examples.push_back(e.str());
    }
  }
  return fit;
}

}  // namespace repose
