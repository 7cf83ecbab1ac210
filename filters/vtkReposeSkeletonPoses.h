#ifndef vtkReposeSkeletonPoses_h
#define vtkReposeSkeletonPoses_h
// The poses a script gives one skeleton, as the pose.json texts vtkReposeSkinning takes:
// - CheckPoseJSON: a pose.json text checked against the skeleton (unknown joints, NaN, zero axes)
//   exactly as `repose pose` checks it;
// - LoadBVH + GetFramePoseJSON: a BVH clip retargeted onto the skeleton (repose::BvhRetargeter)
//   exactly as `repose animate` does, so a frame posed from this text equals that frame of animate.
// Errors: the calls return 0 (or an empty text) and GetLastError() holds one line naming the file.

#include "ReposeFiltersModule.h"
#include "vtkObject.h"

#include <memory>
#include <string>

class REPOSEFILTERS_EXPORT vtkReposeSkeletonPoses : public vtkObject
{
public:
  static vtkReposeSkeletonPoses* New();
  vtkTypeMacro(vtkReposeSkeletonPoses, vtkObject);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  /// skeleton.json text (required before any other call).
  vtkSetStdStringFromCharMacro(SkeletonJSON);
  vtkGetCharFromStdStringMacro(SkeletonJSON);

  /// 1 when `poseJson` parses and names only joints of the skeleton; `name` (a file) leads the error.
  int CheckPoseJSON(const char* poseJson, const char* name);

  /// Retargeting settings, as `repose animate`: a joint map file ({"BVH joint": "skeleton joint"};
  /// empty = the built-in CMU names), "direction" or "relative" mode, its reference frame, whether
  /// the root follows the clip's displacement, millimetres per BVH unit (0: inferred from its leg length).
  vtkSetStdStringFromCharMacro(JointMapFileName);
  vtkGetCharFromStdStringMacro(JointMapFileName);
  vtkSetStdStringFromCharMacro(RetargetMode);
  vtkGetCharFromStdStringMacro(RetargetMode);
  vtkSetMacro(ReferenceFrame, int);
  vtkGetMacro(ReferenceFrame, int);
  vtkSetMacro(TranslateRoot, bool);
  vtkGetMacro(TranslateRoot, bool);
  vtkSetMacro(UnitScaleMm, double);
  vtkGetMacro(UnitScaleMm, double);

  /// Reads the clip and prepares its retargeting with the settings above; 1 on success.
  int LoadBVH(const char* fileName);
  /// Frames of the loaded clip (0 before LoadBVH succeeds) and seconds per frame.
  vtkGetMacro(NumberOfFrames, int);
  vtkGetMacro(FrameTime, double);
  /// pose.json text of frame `frame` of the loaded clip; empty on error.
  const char* GetFramePoseJSON(int frame);

  /// One line on the last failure, empty after success.
  const char* GetLastError() { return this->LastError.c_str(); }

protected:
  vtkReposeSkeletonPoses();
  ~vtkReposeSkeletonPoses() override;

  std::string SkeletonJSON;
  std::string JointMapFileName;
  std::string RetargetMode = "direction";
  int ReferenceFrame = 0;
  bool TranslateRoot = true;
  double UnitScaleMm = 0;  // inferred from the clip's proportions
  int NumberOfFrames = 0;
  double FrameTime = 0;
  std::string FramePose;
  std::string LastError;

  struct Clip;
  std::unique_ptr<Clip> Loaded;

private:
  vtkReposeSkeletonPoses(const vtkReposeSkeletonPoses&) = delete;
  void operator=(const vtkReposeSkeletonPoses&) = delete;
};

#endif
