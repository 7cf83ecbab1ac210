#include "vtkReposeSkinning.h"

#include "vtkDataArray.h"
#include "vtkDoubleArray.h"
#include "vtkFloatArray.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkSMPTools.h"
#include "vtkSmartPointer.h"
#include "vtkUnsignedShortArray.h"
#include "vtkUnstructuredGrid.h"

#include "ReposeWeightArrays.h"
#include "pose.h"
#include "skeleton.h"
#include "ReposeMeshConversion.h"
#include "skinning.h"
#include "array_names.h"

#include <algorithm>
#include <string>
#include <chrono>
#include <cmath>
#include <cstring>
#include <stdexcept>

vtkStandardNewMacro(vtkReposeSkinning);

// Core-typed cache of the input, rebuilt only when the input changes.
struct vtkReposeSkinning::Internals
{
  vtkUnstructuredGrid* CachedInput = nullptr;  // identity only, never dereferenced
  vtkMTimeType CachedInputTime = 0;
  repose::SkinningCache Cache;  // float rest positions and sorted weights
  // Output points, reused while the node count is unchanged (no allocation or page faults per pose).
  vtkSmartPointer<vtkPoints> Posed;
  // The skeleton parsed from SkeletonJSON, kept while the text is the same.
  std::string SkeletonText;
  repose::Skeleton Skeleton;
  // A pose given by SetPose (then PoseJSON is null), its text made only if asked for.
  bool HasTypedPose = false;
  repose::Pose TypedPose;
  std::string TypedPoseText;
  // The bone transforms the last successful run skinned with.
  std::vector<Eigen::Isometry3d> Bones;

  void Convert(vtkUnstructuredGrid* input)
  {
    const vtkIdType np = input->GetNumberOfPoints();
    const repose::Points rest = repose_vtk::ToPoints(input->GetPoints());
    repose::SparseWeights weights;
    std::vector<int> fixedBone;
    this->ConvertWeights(input, np, weights, fixedBone);
    this->Cache = repose::makeSkinningCache(rest, weights, fixedBone);
  }

  static void ConvertWeights(vtkUnstructuredGrid* input, vtkIdType np, repose::SparseWeights& Weights,
    std::vector<int>& FixedBone)
  {
    vtkPointData* pd = input->GetPointData();
    Weights = repose_vtk::ToSparseWeights(pd, np);
    FixedBone.clear();
    if (vtkDataArray* f = pd->GetArray(repose::arrays::kFixedBone))
    {
      if (f->GetNumberOfComponents() != 1 || f->GetNumberOfTuples() != np)
        throw std::invalid_argument("point data \"FixedBone\" must have 1 component per node");
      FixedBone.resize(np);
      for (vtkIdType i = 0; i < np; ++i)
        FixedBone[i] = static_cast<int>(f->GetComponent(i, 0));
    }
  }
};

vtkReposeSkinning::vtkReposeSkinning()
  : Internal(new Internals)
{
}

vtkReposeSkinning::~vtkReposeSkinning()
{
  this->SetSkeletonJSON(nullptr);
  this->SetPoseJSON(nullptr);
  delete this->Internal;
}

void vtkReposeSkinning::SetPoseJSON(const char* poseJson)
{
  const bool same = this->PoseJSON && poseJson ? std::strcmp(this->PoseJSON, poseJson) == 0
                                                : this->PoseJSON == poseJson;
  if (same && !this->Internal->HasTypedPose)
    return;
  delete[] this->PoseJSON;
  this->PoseJSON = poseJson ? std::strcpy(new char[std::strlen(poseJson) + 1], poseJson) : nullptr;
  this->Internal->HasTypedPose = false;
  this->Modified();
}

const char* vtkReposeSkinning::GetPoseJSON()
{
  if (!this->Internal->HasTypedPose)
    return this->PoseJSON;
  this->Internal->TypedPoseText = repose::poseToJson(this->Internal->TypedPose);
  return this->Internal->TypedPoseText.c_str();
}

void vtkReposeSkinning::SetPose(const repose::Pose& pose)
{
  this->Internal->TypedPose = repose::canonicalPose(pose);
  this->Internal->HasTypedPose = true;
  delete[] this->PoseJSON;
  this->PoseJSON = nullptr;
  this->Modified();
}

int vtkReposeSkinning::GetNumberOfBoneTransforms()
{
  return static_cast<int>(this->Internal->Bones.size());
}

bool vtkReposeSkinning::GetBoneTransform(int joint, double matrix[16])
{
  if (joint < 0 || joint >= this->GetNumberOfBoneTransforms())
    return false;
  const Eigen::Matrix4d m = this->Internal->Bones[static_cast<std::size_t>(joint)].matrix();
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c)
      matrix[4 * r + c] = m(r, c);
  return true;
}

const char* vtkReposeSkinning::GetSkinningMethodAsString()
{
  return this->SkinningMethod == LinearBlend ? "LinearBlend" : "DualQuaternion";
}

int vtkReposeSkinning::FillInputPortInformation(int, vtkInformation* info)
{
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkUnstructuredGrid");
  return 1;
}

int vtkReposeSkinning::RequestData(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  vtkUnstructuredGrid* input = vtkUnstructuredGrid::GetData(inputVector[0], 0);
  vtkUnstructuredGrid* output = vtkUnstructuredGrid::GetData(outputVector, 0);
  this->LastError.clear();
  if (!input || !output)
  {
    this->LastError = "missing input or output";
    vtkErrorMacro(<< this->LastError);
    return 0;
  }
  Internals& in = *this->Internal;
  try
  {
    if (!this->SkeletonJSON || !*this->SkeletonJSON)
      throw std::invalid_argument("SkeletonJSON is not set");
    if (in.SkeletonText != this->SkeletonJSON)
    {
      in.SkeletonText.clear();
      in.Skeleton = repose::parseSkeletonJson(this->SkeletonJSON);
      in.SkeletonText = this->SkeletonJSON;
    }
    const repose::Skeleton& skeleton = in.Skeleton;
    const repose::Pose pose = in.HasTypedPose ? in.TypedPose
      : (this->PoseJSON && *this->PoseJSON)   ? repose::parsePoseJson(this->PoseJSON)
                                              : repose::Pose{};
    std::vector<Eigen::Isometry3d> bones = repose::forwardKinematics(skeleton, pose);

    this->LastRunUsedCache = in.CachedInput == input && in.CachedInputTime == input->GetMTime();
    if (!this->LastRunUsedCache)
    {
      in.CachedInput = nullptr;
      in.Convert(input);
      in.CachedInput = input;
      in.CachedInputTime = input->GetMTime();
    }

    const vtkIdType np = static_cast<vtkIdType>(in.Cache.nodeCount());
    if (!in.Posed || in.Posed->GetNumberOfPoints() != np)
    {
      in.Posed = vtkSmartPointer<vtkPoints>::New();
      in.Posed->SetDataTypeToFloat();
      in.Posed->SetNumberOfPoints(np);
    }
    float* dst = vtkArrayDownCast<vtkFloatArray>(in.Posed->GetData())->GetPointer(0);
    const auto t0 = Clock::now();
    repose::skinNodes(in.Cache, bones,
      this->SkinningMethod == LinearBlend ? repose::SkinningMethod::LinearBlend
                                          : repose::SkinningMethod::DualQuaternion,
      dst);
    this->LastSkinningTime = std::chrono::duration<double>(Clock::now() - t0).count();
    // Same points object, new contents: mark it (and its array) modified for renderers/bounds.
    in.Posed->GetData()->Modified();
    in.Posed->Modified();

    output->ShallowCopy(input);
    output->SetPoints(in.Posed);
    in.Bones = std::move(bones);
  }
  catch (const std::exception& e)
  {
    this->LastError = e.what();
    vtkErrorMacro(<< "skinning: " << e.what());
    return 0;
  }
  this->LastExecuteTime = std::chrono::duration<double>(Clock::now() - start).count();
  return 1;
}

void vtkReposeSkinning::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "SkeletonJSON: " << (this->SkeletonJSON ? "(set)" : "(none)") << "\n";
  const char* pose = this->GetPoseJSON();
  os << indent << "PoseJSON: " << (pose ? pose : "(rest pose)") << "\n";
  os << indent << "SkinningMethod: " << this->GetSkinningMethodAsString() << "\n";
  os << indent << "LastSkinningTime: " << this->LastSkinningTime << "\n";
}
