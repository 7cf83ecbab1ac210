#ifndef vtkReposeDicomSegWriter_h
#define vtkReposeDicomSegWriter_h
// Writes a label volume as a DICOM Segmentation object (binary, one segment per label added with
// AddSegment: its name, colour and whether it is bone), the frames positioned in the patient frame.
// The patient, study and frame of reference come from the input's field data "DicomTags" (as a
// DICOM CT's reader fills them; see vtkReposeImageReader), so a viewer overlays the segmentation
// on that CT. Written under a temporary name and renamed into place.

#include "ReposeVolumeModule.h"
#include "vtkReposeWriterBase.h"

#include <memory>
#include <string>

class REPOSEVOLUME_EXPORT vtkReposeDicomSegWriter : public vtkReposeWriterBase
{
public:
  static vtkReposeDicomSegWriter* New();
  vtkTypeMacro(vtkReposeDicomSegWriter, vtkReposeWriterBase);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  vtkSetStringMacro(SeriesDescription);
  vtkGetStringMacro(SeriesDescription);

  /// A label to write: its value in the volume, name, sRGB colour in [0, 1], bone or tissue.
  void AddSegment(int value, const char* name, double r, double g, double b, bool bone);
  void RemoveAllSegments();

protected:
  vtkReposeDicomSegWriter();
  ~vtkReposeDicomSegWriter() override;

  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  char* SeriesDescription = nullptr;
  struct Segments;
  std::unique_ptr<Segments> Table;

private:
  vtkReposeDicomSegWriter(const vtkReposeDicomSegWriter&) = delete;
  void operator=(const vtkReposeDicomSegWriter&) = delete;
};

#endif
