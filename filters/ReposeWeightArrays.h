#ifndef ReposeWeightArrays_h
#define ReposeWeightArrays_h
// The rest mesh's point data "Weights" / "BoneIds" (vtkReposeBoneWeights' output) as core sparse
// weights, shared by the filters. Header-only and not wrapped: it returns a core type.

#include "vtkDataArray.h"
#include "vtkFloatArray.h"
#include "vtkPointData.h"
#include "vtkUnsignedShortArray.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "sparse_weights.h"
#include "array_names.h"

namespace repose_vtk
{

/// Whether the point data holds both weight arrays (their consistency is checked by ToSparseWeights).
inline bool HasWeightArrays(vtkPointData* pd)
{
  return pd->GetArray(repose::arrays::kWeights) && pd->GetArray(repose::arrays::kBoneIds);
}

/// Throws std::invalid_argument when the arrays are missing, disagree in size with each other or
/// with np, or a bone id is not a bone index.
inline repose::SparseWeights ToSparseWeights(vtkPointData* pd, vtkIdType np)
{
  vtkDataArray* w = pd->GetArray(repose::arrays::kWeights);
  vtkDataArray* b = pd->GetArray(repose::arrays::kBoneIds);
  if (!w || !b)
    throw std::invalid_argument(
      "input lacks point data \"Weights\" and \"BoneIds\" (run vtkReposeBoneWeights first)");
  const int k = w->GetNumberOfComponents();
  if (b->GetNumberOfComponents() != k || w->GetNumberOfTuples() != np || b->GetNumberOfTuples() != np)
    throw std::invalid_argument("point data \"Weights\" and \"BoneIds\" disagree in size");
  repose::SparseWeights weights;
  weights.k = k;
  weights.weight.resize(std::size_t(np) * k);
  weights.bone.resize(std::size_t(np) * k);
  // Fast path for vtkReposeBoneWeights' own array types.
  auto* wf = vtkFloatArray::FastDownCast(w);
  auto* bu = vtkUnsignedShortArray::FastDownCast(b);
  if (wf && bu)
  {
    const std::size_t n = std::size_t(np) * k;
    std::copy(wf->GetPointer(0), wf->GetPointer(0) + n, weights.weight.begin());
    std::copy(bu->GetPointer(0), bu->GetPointer(0) + n, weights.bone.begin());
    return weights;
  }
  for (vtkIdType i = 0; i < np; ++i)
  {
    for (int c = 0; c < k; ++c)
    {
      const std::size_t s = std::size_t(i) * k + c;
      weights.weight[s] = static_cast<float>(w->GetComponent(i, c));
      const double bone = b->GetComponent(i, c);
      if (bone < 0 || bone > 65535 || bone != std::floor(bone))
        throw std::invalid_argument(
          "BoneIds of node " + std::to_string(i) + " holds " + std::to_string(bone) + ", not a bone index");
      weights.bone[s] = static_cast<std::uint16_t>(bone);
    }
  }
  return weights;
}

} // namespace repose_vtk

#endif
