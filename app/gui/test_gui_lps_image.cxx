// Display copies in patient coordinates: every voxel of the copy holds, at its world position, the
// value the input has at the same physical (LPS) point, for the directions scanners write (flips and
// axis permutations: exact) and an oblique one (resampled). No display.
#include <Eigen/Core>
#include <QtTest>
#include <vtkImageData.h>
#include <vtkMatrix3x3.h>
#include <vtkPointData.h>

#include "lps_image.h"

using namespace repose;

namespace {
/// A 4x5x6 image whose value encodes its voxel, with the given direction (rows = world axes).
vtkSmartPointer<vtkImageData> makeImage(const double direction[9]) {
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->SetExtent(2, 5, -1, 3, 0, 5);  // an extent not starting at 0, as posed grids have
  image->SetOrigin(10, -20, 30);
  image->SetSpacing(1.5, 2.0, 3.0);
  image->SetDirectionMatrix(direction);
  image->AllocateScalars(VTK_SHORT, 1);
  int e[6];
  image->GetExtent(e);
  for (int k = e[4]; k <= e[5]; ++k)
    for (int j = e[2]; j <= e[3]; ++j)
      for (int i = e[0]; i <= e[1]; ++i) image->SetScalarComponentFromDouble(i, j, k, 0, 100 * k + 10 * j + i);
  return image;
}

/// Checks that the copy's voxel at each input voxel's physical point holds that voxel's value.
void checkSamePlaces(vtkImageData* in, vtkImageData* out) {
  QCOMPARE(out->GetDirectionMatrix()->IsIdentity(), true);
  int e[6], outExtent[6];
  in->GetExtent(e);
  out->GetExtent(outExtent);
  QCOMPARE(outExtent[0], 0);
  for (int k = e[4]; k <= e[5]; ++k)
    for (int j = e[2]; j <= e[3]; ++j)
      for (int i = e[0]; i <= e[1]; ++i) {
        double p[3], u[3];
        const int ijk[3] = {i, j, k};
        in->TransformIndexToPhysicalPoint(ijk, p);
        int o[3];
        for (int a = 0; a < 3; ++a) {
          u[a] = (p[a] - out->GetOrigin()[a]) / out->GetSpacing()[a];
          o[a] = int(std::lround(u[a]));
        }
        QVERIFY2((Eigen::Vector3d(u[0], u[1], u[2]) - Eigen::Vector3d(o[0], o[1], o[2])).norm() < 1e-9, "not on a voxel");
        QCOMPARE(out->GetScalarComponentAsDouble(o[0], o[1], o[2], 0), in->GetScalarComponentAsDouble(i, j, k, 0));
      }
}
}  // namespace

class TestLpsImage : public QObject {
  Q_OBJECT
private slots:
  void flipsAndPermutationsAreExact() {
    const double flip[9] = {-1, 0, 0, 0, -1, 0, 0, 0, 1};  // NIfTI from a scanner, read by ITK
    const double permute[9] = {0, 0, 1, -1, 0, 0, 0, -1, 0};
    const double identity[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    for (const double* d : {flip, permute, identity}) {
      auto in = makeImage(d);
      auto out = lpsAlignedImage(in, true);
      QCOMPARE(out->GetScalarType(), VTK_SHORT);
      checkSamePlaces(in, out);
    }
  }

  void obliqueIsResampled() {
    // 30 degrees about z: nearest sampling returns the input's value at every input voxel centre
    // that falls on the copy's grid within a third of a voxel, and the copy covers the whole image.
    const double c = std::cos(M_PI / 6), s = std::sin(M_PI / 6);
    const double oblique[9] = {c, -s, 0, s, c, 0, 0, 0, 1};
    auto in = makeImage(oblique);
    auto out = lpsAlignedImage(in, true, -1);
    int matched = 0, inside = 0;
    int e[6];
    in->GetExtent(e);
    for (int k = e[4]; k <= e[5]; ++k)
      for (int j = e[2]; j <= e[3]; ++j)
        for (int i = e[0]; i <= e[1]; ++i) {
          double p[3];
          const int ijk[3] = {i, j, k};
          in->TransformIndexToPhysicalPoint(ijk, p);
          int o[3];
          bool close = true;
          for (int a = 0; a < 3; ++a) {
            const double u = (p[a] - out->GetOrigin()[a]) / out->GetSpacing()[a];
            o[a] = int(std::lround(u));
            close = close && std::fabs(u - o[a]) < 0.3 && o[a] >= 0 && o[a] < out->GetDimensions()[a];
          }
          if (!close) continue;
          ++inside;
          matched += out->GetScalarComponentAsDouble(o[0], o[1], o[2], 0) == in->GetScalarComponentAsDouble(i, j, k, 0);
        }
    QVERIFY(inside > 10);
    QCOMPARE(matched, inside);
    QVERIFY(lpsAlignedImage(nullptr, true) == nullptr);
  }
};

QTEST_GUILESS_MAIN(TestLpsImage)
#include "test_gui_lps_image.moc"
