#ifndef vtkReposeAutoRig_h
#define vtkReposeAutoRig_h
// Automatic skeleton (repose::autoRig) from a label image's bone labels.
//
// Input port 0: label image (integer scalars; origin, spacing and direction honoured).
// Output port 0: the label image with every label holding several bones split (its largest
// component keeps the value, the others get new values); the skeleton refers to these values, so
// write this image together with the skeleton. Equal to the input when nothing was split.
// After Update(): GetSkeletonJSON() (skeleton.json text, meant to be edited by hand),
// GetOutputLabelTableTSV() (the table with the split bones' names) and GetReport() (joints, bones
// cut by the field of view, bones left out, missing bones).

#include "ReposeFiltersModule.h"
#include "vtkImageAlgorithm.h"

#include <string>

class REPOSEFILTERS_EXPORT vtkReposeAutoRig : public vtkImageAlgorithm
{
public:
  static vtkReposeAutoRig* New();
  vtkTypeMacro(vtkReposeAutoRig, vtkImageAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  /// Label table text (value<TAB>name[<TAB>kind] lines); empty (default) = TotalSegmentator's
  /// "total" class names.
  vtkSetStdStringFromCharMacro(LabelTableTSV);
  vtkGetCharFromStdStringMacro(LabelTableTSV);

  /// Largest surface gap (mm) between adjacent bones (default 6); the limit is at least
  /// MaxGapVoxels (default 2) voxels of the largest spacing.
  vtkSetClampMacro(MaxGapMm, double, 0.0, 1000.0);
  vtkGetMacro(MaxGapMm, double);
  vtkSetClampMacro(MaxGapVoxels, double, 0.0, 100.0);
  vtkGetMacro(MaxGapVoxels, double);

  /// Results of the last run.
  vtkGetCharFromStdStringMacro(SkeletonJSON);
  vtkGetCharFromStdStringMacro(Report);
  vtkGetCharFromStdStringMacro(OutputLabelTableTSV);
  vtkGetMacro(NumberOfJoints, int);
  vtkGetMacro(Seconds, double);

protected:
  vtkReposeAutoRig();
  ~vtkReposeAutoRig() override = default;

  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  std::string LabelTableTSV;
  double MaxGapMm = 6.0;
  double MaxGapVoxels = 2.0;
  std::string SkeletonJSON;
  std::string Report;
  std::string OutputLabelTableTSV;
  int NumberOfJoints = 0;
  double Seconds = 0;

private:
  vtkReposeAutoRig(const vtkReposeAutoRig&) = delete;
  void operator=(const vtkReposeAutoRig&) = delete;
};

#endif
