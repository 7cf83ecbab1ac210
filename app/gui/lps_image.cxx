#include "lps_image.h"

#include <algorithm>
#include <cmath>

#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkMatrix3x3.h>
#include <vtkPointData.h>
#include <vtkSMPTools.h>

namespace repose {
namespace {

struct Grid {
  int dims[3];
  double origin[3], spacing[3];
  double D[3][3];  // direction, rows = world axes
  int lo[3];       // extent minimum
};

Grid gridOf(vtkImageData* image) {
  Grid g;
  int e[6];
  image->GetExtent(e);
  image->GetOrigin(g.origin);
  image->GetSpacing(g.spacing);
  for (int a = 0; a < 3; ++a) {
    g.dims[a] = e[2 * a + 1] - e[2 * a] + 1;
    g.lo[a] = e[2 * a];
    for (int b = 0; b < 3; ++b) g.D[a][b] = image->GetDirectionMatrix()->GetElement(a, b);
  }
  return g;
}

/// World point of the input's voxel whose offsets from the extent minimum are `u`.
void worldOf(const Grid& g, const double u[3], double w[3]) {
  for (int r = 0; r < 3; ++r) {
    w[r] = g.origin[r];
    for (int c = 0; c < 3; ++c) w[r] += g.D[r][c] * g.spacing[c] * (g.lo[c] + u[c]);
  }
}

/// Input axis feeding each world axis and its sign; false unless the direction is a signed permutation.
bool signedPermutation(const Grid& g, int axisOf[3], int sign[3]) {
  for (int r = 0; r < 3; ++r) {
    axisOf[r] = -1;
    for (int c = 0; c < 3; ++c)
      if (std::fabs(std::fabs(g.D[r][c]) - 1) < 1e-6) axisOf[r] = c, sign[r] = g.D[r][c] > 0 ? 1 : -1;
    if (axisOf[r] < 0) return false;
  }
  return axisOf[0] != axisOf[1] && axisOf[1] != axisOf[2] && axisOf[0] != axisOf[2];
}

template <class T>
void reorder(const T* in, T* out, const Grid& g, const int axisOf[3], const int sign[3], const int outDims[3], int nc) {
  const long long inStride[3] = {1, g.dims[0], (long long)g.dims[0] * g.dims[1]};
  vtkSMPTools::For(0, outDims[2], [&](int k0, int k1) {
    for (int k = k0; k < k1; ++k)
      for (int j = 0; j < outDims[1]; ++j)
        for (int i = 0; i < outDims[0]; ++i) {
          const int u[3] = {i, j, k};
          long long src = 0;
          for (int r = 0; r < 3; ++r) {
            const int c = axisOf[r];
            src += inStride[c] * (sign[r] > 0 ? u[r] : g.dims[c] - 1 - u[r]);
          }
          const long long dst = i + (long long)outDims[0] * (j + (long long)outDims[1] * k);
          std::copy(in + src * nc, in + src * nc + nc, out + dst * nc);
        }
  });
}

/// Oblique direction: sample the input at every output voxel centre (first component only).
template <class T>
void resample(const T* in, float* out, const Grid& g, vtkImageData* target, bool nearest, double background) {
  int dims[3];
  double o[3], s[3];
  target->GetDimensions(dims);
  target->GetOrigin(o);
  target->GetSpacing(s);
  auto value = [&](int i, int j, int k) -> double {
    if (i < 0 || j < 0 || k < 0 || i >= g.dims[0] || j >= g.dims[1] || k >= g.dims[2]) return background;
    return double(in[i + (long long)g.dims[0] * (j + (long long)g.dims[1] * k)]);
  };
  vtkSMPTools::For(0, dims[2], [&](int k0, int k1) {
    for (int k = k0; k < k1; ++k)
      for (int j = 0; j < dims[1]; ++j)
        for (int i = 0; i < dims[0]; ++i) {
          const double w[3] = {o[0] + s[0] * i, o[1] + s[1] * j, o[2] + s[2] * k};
          double u[3];  // continuous offsets from the extent minimum: D^T (w - origin) / spacing - lo
          for (int c = 0; c < 3; ++c) {
            double d = 0;
            for (int r = 0; r < 3; ++r) d += g.D[r][c] * (w[r] - g.origin[r]);
            u[c] = d / g.spacing[c] - g.lo[c];
          }
          double v;
          if (nearest) {
            v = value(int(std::lround(u[0])), int(std::lround(u[1])), int(std::lround(u[2])));
          } else {
            const int b[3] = {int(std::floor(u[0])), int(std::floor(u[1])), int(std::floor(u[2]))};
            const double f[3] = {u[0] - b[0], u[1] - b[1], u[2] - b[2]};
            v = 0;
            for (int corner = 0; corner < 8; ++corner) {
              const int dx = corner & 1, dy = (corner >> 1) & 1, dz = corner >> 2;
              const double weight = (dx ? f[0] : 1 - f[0]) * (dy ? f[1] : 1 - f[1]) * (dz ? f[2] : 1 - f[2]);
              if (weight > 0) v += weight * value(b[0] + dx, b[1] + dy, b[2] + dz);
            }
          }
          out[i + (long long)dims[0] * (j + (long long)dims[1] * k)] = float(v);
        }
  });
}

}  // namespace

vtkSmartPointer<vtkImageData> lpsAlignedImage(vtkImageData* image, bool nearest, double background) {
  if (!image || !image->GetPointData()->GetScalars()) return nullptr;
  const Grid g = gridOf(image);
  vtkDataArray* scalars = image->GetPointData()->GetScalars();
  const int nc = scalars->GetNumberOfComponents();
  auto out = vtkSmartPointer<vtkImageData>::New();
  int axisOf[3], sign[3];
  if (signedPermutation(g, axisOf, sign)) {
    // Exact: the voxel at the lowest world coordinate of every axis comes first.
    int dims[3];
    double corner[3], s[3], origin[3];
    for (int r = 0; r < 3; ++r) {
      dims[r] = g.dims[axisOf[r]];
      s[r] = g.spacing[axisOf[r]];
    }
    for (int c = 0; c < 3; ++c)
      for (int r = 0; r < 3; ++r)
        if (axisOf[r] == c) corner[c] = sign[r] > 0 ? 0 : g.dims[c] - 1;
    worldOf(g, corner, origin);
    out->SetDimensions(dims);
    out->SetSpacing(s);
    out->SetOrigin(origin);
    const bool identity = axisOf[0] == 0 && axisOf[1] == 1 && axisOf[2] == 2 && sign[0] > 0 && sign[1] > 0 && sign[2] > 0;
    if (identity) {  // same voxel order: share the scalars
      out->GetPointData()->SetScalars(scalars);
      return out;
    }
    vtkSmartPointer<vtkDataArray> copy;
    copy.TakeReference(scalars->NewInstance());
    copy->SetName(scalars->GetName());
    copy->SetNumberOfComponents(nc);
    copy->SetNumberOfTuples(scalars->GetNumberOfTuples());
    switch (scalars->GetDataType()) {
      vtkTemplateMacro(reorder(static_cast<const VTK_TT*>(scalars->GetVoidPointer(0)),
                               static_cast<VTK_TT*>(copy->GetVoidPointer(0)), g, axisOf, sign, dims, nc));
    }
    out->GetPointData()->SetScalars(copy);
    return out;
  }
  // Oblique: an axis-aligned grid over the image's corners, spacing the direction-weighted input spacing.
  double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300}, s[3];
  for (int corner = 0; corner < 8; ++corner) {
    const double u[3] = {double((corner & 1) ? g.dims[0] - 1 : 0), double((corner & 2) ? g.dims[1] - 1 : 0),
                         double((corner & 4) ? g.dims[2] - 1 : 0)};
    double w[3];
    worldOf(g, u, w);
    for (int r = 0; r < 3; ++r) lo[r] = std::min(lo[r], w[r]), hi[r] = std::max(hi[r], w[r]);
  }
  int dims[3];
  for (int r = 0; r < 3; ++r) {
    s[r] = 0;
    for (int c = 0; c < 3; ++c) s[r] += std::fabs(g.D[r][c]) * g.spacing[c];
    dims[r] = std::max(1, int(std::ceil((hi[r] - lo[r]) / s[r] - 1e-6)) + 1);
  }
  out->SetDimensions(dims);
  out->SetSpacing(s);
  out->SetOrigin(lo);
  out->AllocateScalars(VTK_FLOAT, 1);
  float* dst = static_cast<float*>(out->GetScalarPointer());
  switch (scalars->GetDataType()) {
    vtkTemplateMacro(resample(static_cast<const VTK_TT*>(scalars->GetVoidPointer(0)), dst, g, out, nearest, background));
  }
  return out;
}

}  // namespace repose
