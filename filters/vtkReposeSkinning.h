#ifndef vtkReposeSkinning_h
#define vtkReposeSkinning_h
// Poses a weighted tet mesh: forward kinematics of SkeletonJSON + PoseJSON, then dual-quaternion
// (default) or linear-blend skinning of every node. Input: the output of vtkReposeBoneWeights
// (point data "Weights", "BoneIds", optional "FixedBone": fixed nodes move rigidly with their bone).
// Output: same topology and data, posed float points (~1e-4 mm rounding at 1 m coordinates).
// C++ callers that pose every frame give a typed pose (SetPose) and read back the bone transforms
// the mesh was skinned with (GetBoneTransform): no text and one pass of forward kinematics per frame.
// The rest points and weights are converted once per input change (to a compact float cache); a new
// pose (or method) only re-runs the skinning itself, in place: the output vtkPoints object is reused
// (and marked Modified) while the node count is unchanged, so a consumer holding on to an earlier
// output's points sees them change; deep-copy the output to keep a pose.

#include "ReposeFiltersModule.h"
#include "vtkUnstructuredGridAlgorithm.h"

#include <string>

#ifndef __VTK_WRAP__
namespace repose
{
struct Pose;  // pose.h
}
#endif

class REPOSEFILTERS_EXPORT vtkReposeSkinning : public vtkUnstructuredGridAlgorithm
{
public:
  static vtkReposeSkinning* New();
  vtkTypeMacro(vtkReposeSkinning, vtkUnstructuredGridAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  enum SkinningMethodType
  {
    DualQuaternion = 0,
    LinearBlend = 1
  };

  /// skeleton.json text (required).
  vtkSetStringMacro(SkeletonJSON);
  vtkGetStringMacro(SkeletonJSON);
  /// pose.json text; empty means the rest pose. Replaces a pose given by SetPose.
  virtual void SetPoseJSON(const char* poseJson);
  /// The pose as pose.json text (a pose given by SetPose comes back exact, as quaternions).
  virtual const char* GetPoseJSON();
#ifndef __VTK_WRAP__
  /// A typed pose (pose.h), for C++ callers that pose every frame without text on the way: the mesh
  /// comes out bit for bit as from SetPoseJSON(poseToJson(pose)). Throws std::invalid_argument on a
  /// zero or non-finite rotation; joint names are checked when the filter runs.
  void SetPose(const repose::Pose& pose);
#endif
  /// The bone transforms of the last successful run (rest -> posed, mm; one per joint in the
  /// skeleton's order): what the mesh was skinned with, so a view can draw the skeleton without
  /// running forward kinematics again. 0 before the first run.
  int GetNumberOfBoneTransforms();
  /// Joint `joint`'s transform as a row-major 4x4 matrix; false if there is no such joint.
  bool GetBoneTransform(int joint, double matrix[16]);

  vtkSetClampMacro(SkinningMethod, int, DualQuaternion, LinearBlend);
  vtkGetMacro(SkinningMethod, int);
  void SetSkinningMethodToDualQuaternion() { this->SetSkinningMethod(DualQuaternion); }
  void SetSkinningMethodToLinearBlend() { this->SetSkinningMethod(LinearBlend); }
  const char* GetSkinningMethodAsString();

  /// Seconds spent in the core skinning call of the last run.
  vtkGetMacro(LastSkinningTime, double);
  /// Seconds of the whole last RequestData (conversion of a new input included).
  vtkGetMacro(LastExecuteTime, double);
  /// 1 if the last run reused the cached rest points and weights.
  vtkGetMacro(LastRunUsedCache, int);

  /// One-line description of the last failure, empty after success.
  const char* GetLastError() { return this->LastError.c_str(); }

protected:
  vtkReposeSkinning();
  ~vtkReposeSkinning() override;

  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int FillInputPortInformation(int port, vtkInformation* info) override;

  char* SkeletonJSON = nullptr;
  char* PoseJSON = nullptr;
  int SkinningMethod = DualQuaternion;
  double LastSkinningTime = 0;
  double LastExecuteTime = 0;
  int LastRunUsedCache = 0;
  std::string LastError;

  struct Internals;
  Internals* Internal;

private:
  vtkReposeSkinning(const vtkReposeSkinning&) = delete;
  void operator=(const vtkReposeSkinning&) = delete;
};

#endif
