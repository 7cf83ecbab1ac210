#ifndef vtkReposeSurfaceExtractor_h
#define vtkReposeSurfaceExtractor_h
// The rest-pose surfaces shown to the user and bound to the tet mesh: the skin (outline of the
// full, un-peeled body mask) and one closed surface per bone label of the skeleton.
//
// Input port 0: label image (integer scalars; origin, spacing and direction honoured).
// Input port 1 (optional): intensity image (CT) on the same grid; voxels above BodyThreshold join
// the body mask.
// Output: vtkPolyData in physical coordinates (mm), triangles with point normals, cell data "Label"
// (int): -1 for the skin, the label value for a bone surface. Surfaces are windowed-sinc smoothed and
// optionally decimated (TargetReduction).

#include "ReposeFiltersModule.h"
#include "vtkPolyDataAlgorithm.h"

#include <string>

class vtkAlgorithmOutput;
class vtkImageData;
class vtkPolyData;

class REPOSEFILTERS_EXPORT vtkReposeSurfaceExtractor : public vtkPolyDataAlgorithm
{
public:
  static vtkReposeSurfaceExtractor* New();
  vtkTypeMacro(vtkReposeSurfaceExtractor, vtkPolyDataAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  /// Cell-data "Label" value of the skin surface.
  enum { SkinLabel = -1 };

  /// skeleton.json text; the bones are the labels listed by its joints.
  vtkSetStdStringFromCharMacro(SkeletonJSON);
  vtkGetCharFromStdStringMacro(SkeletonJSON);

  /// HU above which CT voxels belong to the body (used only with an intensity input). Default -500.
  vtkSetMacro(BodyThreshold, double);
  vtkGetMacro(BodyThreshold, double);

  /// Output the skin surface (default on) and the bone surfaces (default on).
  vtkSetMacro(ExtractSkin, bool);
  vtkGetMacro(ExtractSkin, bool);
  vtkBooleanMacro(ExtractSkin, bool);
  vtkSetMacro(ExtractBones, bool);
  vtkGetMacro(ExtractBones, bool);
  vtkBooleanMacro(ExtractBones, bool);

  /// Windowed-sinc smoothing iterations (0 = none; default 15) and pass band (default 0.1).
  vtkSetClampMacro(SmoothingIterations, int, 0, 1000);
  vtkGetMacro(SmoothingIterations, int);
  vtkSetClampMacro(PassBand, double, 0.001, 2.0);
  vtkGetMacro(PassBand, double);

  /// Fraction of triangles removed by quadric decimation (0 = none, default; e.g. 0.7).
  vtkSetClampMacro(TargetReduction, double, 0.0, 0.99);
  vtkGetMacro(TargetReduction, double);

  /// Optional intensity image (CT) on the label grid.
  void SetIntensityConnection(vtkAlgorithmOutput* port) { this->SetInputConnection(1, port); }
  void SetIntensityData(vtkImageData* image);

  /// Contours a binary mask image (non-zero = inside; any scalar type) into a closed triangle surface
  /// in physical coordinates: the mask is padded with background so the surface closes at the image
  /// border, contoured in the axis-aligned index frame (VTK 9.1's imaging filters ignore the direction
  /// matrix) and mapped with origin, spacing and direction afterwards. meshingSpacing > the image's
  /// spacing resamples (antialiased) to that spacing first (0 = keep). Returns 1 on success.
  static int ContourMask(vtkImageData* mask, double meshingSpacing, int smoothingIterations, double passBand,
    double targetReduction, vtkPolyData* output);

protected:
  vtkReposeSurfaceExtractor();
  ~vtkReposeSurfaceExtractor() override = default;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  std::string SkeletonJSON;
  double BodyThreshold = -500.0;
  bool ExtractSkin = true;
  bool ExtractBones = true;
  int SmoothingIterations = 15;
  double PassBand = 0.1;
  double TargetReduction = 0.0;

private:
  vtkReposeSurfaceExtractor(const vtkReposeSurfaceExtractor&) = delete;
  void operator=(const vtkReposeSurfaceExtractor&) = delete;
};

#endif
