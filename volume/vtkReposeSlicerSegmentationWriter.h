#ifndef vtkReposeSlicerSegmentationWriter_h
#define vtkReposeSlicerSegmentationWriter_h
// Writes a label volume as a 3D Slicer segmentation (.seg.nrrd): a gzip NRRD of the labels (the
// smallest integer type holding them) whose header names and colours a segment per label added
// with AddSegment, all in one layer (see slicer_segmentation.h).
// Slicer opens it as a segmentation with those names and colours; every NRRD reader reads the
// label map as it is. Written atomically as vtkReposeImageWriter writes.

#include "ReposeVolumeModule.h"
#include "vtkReposeImageWriter.h"

#include <string>
#include <vector>

class REPOSEVOLUME_EXPORT vtkReposeSlicerSegmentationWriter : public vtkReposeImageWriter
{
public:
  static vtkReposeSlicerSegmentationWriter* New();
  vtkTypeMacro(vtkReposeSlicerSegmentationWriter, vtkReposeImageWriter);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  /// A label to write as a segment: its value in the volume (not 0), name, sRGB colour in [0, 1].
  void AddSegment(int value, const char* name, double r, double g, double b);
  void RemoveAllSegments();
  int GetNumberOfSegments() { return static_cast<int>(this->Segments.size()); }

protected:
  vtkReposeSlicerSegmentationWriter();
  ~vtkReposeSlicerSegmentationWriter() override;

  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  std::vector<std::pair<std::string, std::string>> HeaderFields(vtkImageData* written) override;

  struct Segment
  {
    int Value;
    std::string Name;
    double Color[3];
  };
  std::vector<Segment> Segments;

private:
  vtkReposeSlicerSegmentationWriter(const vtkReposeSlicerSegmentationWriter&) = delete;
  void operator=(const vtkReposeSlicerSegmentationWriter&) = delete;
};

#endif
