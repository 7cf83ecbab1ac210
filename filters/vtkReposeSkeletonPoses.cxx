#include "vtkReposeSkeletonPoses.h"

#include "vtkObjectFactory.h"

#include "bvh.h"
#include "pose.h"
#include "retarget.h"
#include "skeleton.h"

#include <exception>

vtkStandardNewMacro(vtkReposeSkeletonPoses);

struct vtkReposeSkeletonPoses::Clip
{
  std::string FileName;
  std::unique_ptr<repose::BvhRetargeter> Retargeter;
};

vtkReposeSkeletonPoses::vtkReposeSkeletonPoses() = default;
vtkReposeSkeletonPoses::~vtkReposeSkeletonPoses() = default;

int vtkReposeSkeletonPoses::CheckPoseJSON(const char* poseJson, const char* name)
{
  this->LastError.clear();
  const std::string what = name && *name ? name : "pose";
  try
  {
    const repose::Skeleton skeleton = repose::parseSkeletonJson(this->SkeletonJSON);
    repose::validatePose(repose::parsePoseJson(poseJson ? poseJson : ""), skeleton);
  }
  catch (const std::exception& e)
  {
    this->LastError = what + ": " + e.what();
    return 0;
  }
  return 1;
}

int vtkReposeSkeletonPoses::LoadBVH(const char* fileName)
{
  this->LastError.clear();
  this->Loaded.reset();
  this->NumberOfFrames = 0;
  this->FrameTime = 0;
  const std::string path = fileName ? fileName : "";
  // Each stage's error names its file as `repose animate` does.
  std::string stage = "skeleton";
  try
  {
    const repose::Skeleton skeleton = repose::parseSkeletonJson(this->SkeletonJSON);
    stage.clear();
    const repose::BvhMotion motion = repose::readBvhFile(path);
    stage = this->JointMapFileName.empty() ? path : std::string();
    const repose::BvhJointMap map = this->JointMapFileName.empty()
      ? repose::defaultCmuJointMap(motion, skeleton)
      : repose::readJointMapFile(this->JointMapFileName);
    stage = path;
    repose::RetargetOptions options;
    options.mode = repose::parseRetargetMode(this->RetargetMode);
    options.referenceFrame = this->ReferenceFrame;
    options.translateRoot = this->TranslateRoot;
    options.unitScaleMm = this->UnitScaleMm;
    auto clip = std::make_unique<Clip>();
    clip->FileName = path;
    clip->Retargeter = std::make_unique<repose::BvhRetargeter>(motion, skeleton, map, options);
    this->NumberOfFrames = motion.frameCount;
    this->FrameTime = motion.frameTime;
    this->Loaded = std::move(clip);
  }
  catch (const std::exception& e)
  {
    this->LastError = (stage.empty() ? std::string() : stage + ": ") + e.what();
    return 0;
  }
  return 1;
}

const char* vtkReposeSkeletonPoses::GetFramePoseJSON(int frame)
{
  this->LastError.clear();
  this->FramePose.clear();
  if (!this->Loaded)
  {
    this->LastError = "no BVH clip loaded";
  }
  else if (frame < 0 || frame >= this->NumberOfFrames)
  {
    this->LastError = this->Loaded->FileName + ": frame " + std::to_string(frame) + " is not in the clip (" +
      std::to_string(this->NumberOfFrames) + " frames)";
  }
  else
  {
    this->FramePose = repose::poseToJson(this->Loaded->Retargeter->pose(frame));
  }
  return this->FramePose.c_str();
}

void vtkReposeSkeletonPoses::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "JointMapFileName: " << this->JointMapFileName << "\n";
  os << indent << "RetargetMode: " << this->RetargetMode << "\n";
  os << indent << "ReferenceFrame: " << this->ReferenceFrame << "\n";
  os << indent << "TranslateRoot: " << this->TranslateRoot << "\n";
  os << indent << "UnitScaleMm: " << this->UnitScaleMm << "\n";
  os << indent << "NumberOfFrames: " << this->NumberOfFrames << "\n";
}
