#include "mesh_budget.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "mesh_tagging.h"
#include "meshing_grid.h"
#include "parallel_for.h"

namespace repose {

SeedSteps seedSteps(const ImageGrid& scan, double spacingMm) {
  const double ratio = std::max(1.0, spacingMm / scan.spacing.minCoeff());
  SeedSteps s;
  s.surface = std::max(2, int(std::lround(2 * ratio)));
  s.interior = 2 * s.surface;
  return s;
}

std::size_t boundaryFaces(const MaskVolume& mask) {
  const ImageGrid& g = mask.grid;
  if (mask.data.size() != g.voxelCount()) throw std::invalid_argument("boundary faces: mask and grid disagree");
  const int nx = g.dims[0], ny = g.dims[1], nz = g.dims[2];
  std::vector<std::size_t> perSlice(std::size_t(std::max(nz, 0)), 0);
  parallelFor(std::size_t(nz), [&](std::size_t kb, std::size_t ke) {
    for (int k = int(kb); k < int(ke); ++k) {
      std::size_t faces = 0;
      for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
          if (!mask.at(i, j, k)) continue;
          faces += (i == 0 || !mask.at(i - 1, j, k)) + (i == nx - 1 || !mask.at(i + 1, j, k)) +
                   (j == 0 || !mask.at(i, j - 1, k)) + (j == ny - 1 || !mask.at(i, j + 1, k)) +
                   (k == 0 || !mask.at(i, j, k - 1)) + (k == nz - 1 || !mask.at(i, j, k + 1));
        }
      perSlice[k] = faces;
    }
  }, 1);
  std::size_t total = 0;
  for (std::size_t f : perSlice) total += f;
  return total;
}

// kTetsPerPoint: TetGen's tets (radius-edge 2, surface kept) per surface face or seed were 7.8 on
// the medium phantom (171 108 faces, 54 605 seeds, 1.76 M tets), 7.3 on the small phantom lying in
// contact, 7.9 on the TotalSegmentator CT, 7.5 on the Visible Human female at 3.7 mm and 10.1 on the
// large phantom: the mesher corrects its spacing once with the ratio it met.
double predictTets(std::size_t surfaceFaces, std::size_t seeds, double tetsPerPoint) {
  return tetsPerPoint * double(surfaceFaces + seeds);
}

MeshSpacingChoice chooseMeshSpacing(const MaskVolume& peeled, const LabelVolume& labels,
                                    const std::vector<int>& boneOfLabel, double maxTets, double tetsPerPoint) {
  if (!(maxTets >= 1000)) throw std::invalid_argument("mesh budget: the tet budget must be at least 1000");
  if (!(tetsPerPoint > 0)) throw std::invalid_argument("mesh budget: the tets per surface point must be positive");
  const ImageGrid& scan = labels.grid;
  auto evaluate = [&](double h, MeshSpacingChoice& c) {
    const MeshingVolumes m = binToMeshingGrid(peeled, labels, boneOfLabel, meshingGrid(scan, h));
    const SeedSteps steps = seedSteps(scan, h);
    c.spacingMm = h;
    c.surfaceFaces = boundaryFaces(m.body);
    c.seeds = std::size_t(boneSeedPoints(labels, boneOfLabel, peeled, steps.surface, steps.interior).rows());
    c.predictedTets = predictTets(c.surfaceFaces, c.seeds, tetsPerPoint);
    ++c.trials;
  };
  MeshSpacingChoice trial, best;
  const double finest = scan.spacing.minCoeff();
  evaluate(finest, trial);
  if (trial.predictedTets <= maxTets) return trial;
  // Faces and seeds both scale about as 1 / h^2: aim a little below the budget, then correct.
  const double target = 0.93 * maxTets;
  double h = finest * std::sqrt(trial.predictedTets / target);
  best.spacingMm = 0;
  int trials = trial.trials;
  for (int round = 0; round < 8; ++round) {
    MeshSpacingChoice c;
    evaluate(h, c);
    trials += c.trials;
    if (c.predictedTets <= maxTets && (best.spacingMm == 0 || h < best.spacingMm)) best = c;
    if (c.predictedTets <= maxTets && c.predictedTets >= 0.85 * maxTets) break;
    h *= std::sqrt(c.predictedTets / target);
  }
  if (best.spacingMm == 0) {  // not converged: take a safe spacing
    evaluate(h * 1.2, best);
  }
  best.trials = trials;
  return best;
}

}  // namespace repose
