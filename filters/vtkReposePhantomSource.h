#ifndef vtkReposePhantomSource_h
#define vtkReposePhantomSource_h
// The built-in procedural phantom: a human-like label volume (int scalars "Labels") in LPS
// (direction diag(-1,-1,1)), with a non-zero origin and anisotropic spacing, and its skeleton.
// Sizes tiny (0), small (1), medium (2), large (3) describe the same body at finer spacing.

#include "ReposeFiltersModule.h"
#include "vtkImageAlgorithm.h"

#include <string>

class REPOSEFILTERS_EXPORT vtkReposePhantomSource : public vtkImageAlgorithm
{
public:
  static vtkReposePhantomSource* New();
  vtkTypeMacro(vtkReposePhantomSource, vtkImageAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  enum
  {
    TINY = 0,
    SMALL = 1,
    MEDIUM = 2,
    LARGE = 3
  };

  vtkSetClampMacro(Size, int, TINY, LARGE);
  vtkGetMacro(Size, int);
  void SetSizeToTiny() { this->SetSize(TINY); }
  void SetSizeToSmall() { this->SetSize(SMALL); }
  void SetSizeToMedium() { this->SetSize(MEDIUM); }
  void SetSizeToLarge() { this->SetSize(LARGE); }
  /// "tiny" | "small" | "medium" | "large"; anything else is an error and keeps the current size.
  void SetSizeName(const char* name);
  const char* GetSizeName();

  /// Rest pose of the scan: APART (arms and thighs clear of each other, the default) or CONTACT
  /// (arms against the torso, hands against the thighs, thighs touching, welded in the voxels).
  enum
  {
    APART = 0,
    CONTACT = 1
  };
  vtkSetClampMacro(RestPose, int, APART, CONTACT);
  vtkGetMacro(RestPose, int);
  void SetRestPoseToApart() { this->SetRestPose(APART); }
  void SetRestPoseToContact() { this->SetRestPose(CONTACT); }
  /// "apart" | "contact"; anything else is an error and keeps the current rest pose.
  void SetRestPoseName(const char* name);
  const char* GetRestPoseName();

  /// The skeleton of the current size as skeleton.json text (true joint centres, mm, LPS).
  const char* GetSkeletonJSON();
  /// Label table: a header line "value\tname\tkind", then one line per label (kind: bone | soft).
  const char* GetLabelTableTSV();

protected:
  vtkReposePhantomSource();
  ~vtkReposePhantomSource() override = default;

  int RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  int Size = TINY;
  int RestPose = APART;
  std::string SkeletonJSON;
  std::string LabelTableTSV;

private:
  vtkReposePhantomSource(const vtkReposePhantomSource&) = delete;
  void operator=(const vtkReposePhantomSource&) = delete;
};

#endif
