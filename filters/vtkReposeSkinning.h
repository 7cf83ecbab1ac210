#ifndef vtkReposeSkinning_h
#define vtkReposeSkinning_h
// Poses a weighted tet mesh: forward kinematics of SkeletonJSON + PoseJSON, then dual-quaternion
// (default) or linear-blend skinning of every node. Input: the output of vtkReposeBoneWeights
// (point data "Weights", "BoneIds", optional "FixedBone": fixed nodes move rigidly with their bone).
// Output: same topology and data, posed float points (~1e-4 mm rounding at 1 m coordinates).
// The rest points and weights are converted once per input change (to a compact float cache); a new
// pose (or method) only re-runs the skinning itself, in place: the output vtkPoints object is reused
// (and marked Modified) while the node count is unchanged, so a consumer holding on to an earlier
// output's points sees them change; deep-copy the output to keep a pose.

#include "ReposeFiltersModule.h"
#include "vtkUnstructuredGridAlgorithm.h"

#include <string>

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
  /// pose.json text; empty means the rest pose.
  vtkSetStringMacro(PoseJSON);
  vtkGetStringMacro(PoseJSON);

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
