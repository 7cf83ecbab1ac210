#include "scan_files.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <stdexcept>

#include <vtkDataArray.h>
#include <vtkIntArray.h>
#include <vtkMatrix3x3.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLPolyDataWriter.h>
#include <vtkXMLUnstructuredGridWriter.h>

#include "array_names.h"
#include "atomic_outputs.h"
#include "checked_write.h"
#include "mesh_io.h"
#include "repose_version.h"
#include "vtkReposeDicomSeriesWriter.h"
#include "vtkReposeImageReader.h"
#include "vtkReposeImageWriter.h"

namespace repose {
namespace {

vtkSmartPointer<vtkImageData> readImageFile(const std::string& path, const std::string& seriesUid = "") {
  if (!fileExists(path)) throw std::runtime_error(path + ": no such file");
  auto reader = vtkSmartPointer<vtkReposeImageReader>::New();
  reader->SetFileName(path.c_str());
  if (!seriesUid.empty()) reader->SetSeriesUID(seriesUid.c_str());
  reader->Update();
  if (reader->GetLastError() && *reader->GetLastError())
    throw std::runtime_error(reader->GetLastError());
  vtkImageData* out = reader->GetOutput();
  if (!out || !out->GetPointData()->GetScalars())
    throw std::runtime_error(path + ": cannot read image");
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->ShallowCopy(out);
  return image;
}

}  // namespace

std::string describeGrid(vtkImageData* image) {
  int d[3];
  double o[3], s[3];
  image->GetDimensions(d);
  image->GetOrigin(o);
  image->GetSpacing(s);
  std::ostringstream m;
  m << d[0] << "x" << d[1] << "x" << d[2] << " voxels of " << s[0] << "x" << s[1] << "x" << s[2]
    << " mm at (" << o[0] << ", " << o[1] << ", " << o[2] << ")";
  return m.str();
}

vtkSmartPointer<vtkImageData> readLabelVolume(const std::string& path) {
  // A folder would be read as a DICOM CT series and its outputs written as one: labels are files.
  if (std::filesystem::is_directory(path))
    throw std::runtime_error(path + ": a folder; label volumes are read from files (NIfTI, NRRD, MetaImage)");
  vtkSmartPointer<vtkImageData> image = readImageFile(path);
  vtkDataArray* scalars = image->GetPointData()->GetScalars();
  if (scalars->GetNumberOfComponents() != 1)
    throw std::runtime_error(path + ": label volume must have one component per voxel, not " +
                             std::to_string(scalars->GetNumberOfComponents()));
  if (scalars->GetDataType() != VTK_INT) {
    // Float files holding whole numbers are common for label maps; anything else is not a label map.
    const vtkIdType n = scalars->GetNumberOfTuples();
    auto labels = vtkSmartPointer<vtkIntArray>::New();
    labels->SetName(repose::arrays::kLabels);
    labels->SetNumberOfTuples(n);
    for (vtkIdType i = 0; i < n; ++i) {
      const double v = scalars->GetTuple1(i);
      if (!std::isfinite(v) || v != std::floor(v) || std::fabs(v) > 2147483647.0)
        throw std::runtime_error(path + ": not a label volume (voxel value " + std::to_string(v) +
                                 " is not an integer)");
      labels->SetValue(i, static_cast<int>(v));
    }
    image->GetPointData()->SetScalars(labels);
  }
  vtkIntArray* labels = vtkIntArray::SafeDownCast(image->GetPointData()->GetScalars());
  labels->SetName(repose::arrays::kLabels);
  // Tables indexed by label value are sized by the largest label: bound it before anyone allocates.
  bool any = false;
  for (vtkIdType i = 0, n = labels->GetNumberOfTuples(); i < n; ++i) {
    const int v = labels->GetValue(i);
    if (v < 0 || v > kMaxLabelValue)
      throw std::runtime_error(path + ": label " + std::to_string(v) + " is outside 0.." +
                               std::to_string(kMaxLabelValue) + " (not a label volume, or a damaged one)");
    any = any || v != 0;
  }
  if (!any) throw std::runtime_error(path + ": empty label volume (every voxel is 0)");
  return image;
}

vtkSmartPointer<vtkImageData> readIntensityImage(const std::string& path, const std::string& seriesUid) {
  vtkSmartPointer<vtkImageData> image = readImageFile(path, seriesUid);
  if (image->GetPointData()->GetScalars()->GetNumberOfComponents() != 1)
    throw std::runtime_error(path + ": image must have one component per voxel");
  return image;
}

namespace {
void writeImageAs(vtkImageData* image, const std::string& path, bool smallestIntegerType) {
  const QuietStderr quiet;
  auto writer = vtkSmartPointer<vtkReposeImageWriter>::New();
  writer->SetFileName(path.c_str());
  writer->SetSmallestIntegerType(smallestIntegerType);
  writer->SetInputData(image);
  if (!writer->Write()) {
    const char* err = writer->GetLastError();
    throw std::runtime_error(err && *err ? std::string(err) : path + ": cannot write image");
  }
}
}  // namespace

void writeImage(vtkImageData* image, const std::string& path) {
  if (!path.empty() && path.back() == '/') {  // a DICOM CT series, as the input was
    const QuietStderr quiet;
    auto writer = vtkSmartPointer<vtkReposeDicomSeriesWriter>::New();
    writer->SetFileName(path.substr(0, path.size() - 1).c_str());
    writer->SetSeriesDescription("Reposed (Repose " REPOSE_VERSION ")");
    writer->SetInputData(image);
    if (!writer->Write()) throw std::runtime_error(writer->GetLastError());
    return;
  }
  writeImageAs(image, path, false);
}

void writeLabelImage(vtkImageData* labels, const std::string& path) { writeImageAs(labels, path, true); }

void writeMesh(vtkUnstructuredGrid* mesh, const std::string& path) {
  writeVtkXml<vtkXMLUnstructuredGridWriter>(mesh, path);
}

void writeSurfaces(vtkPolyData* surfaces, const std::string& path) { writeVtkXml<vtkXMLPolyDataWriter>(surfaces, path); }

void checkSameGrid(vtkImageData* labels, const std::string& labelsName, vtkImageData* image,
                   const std::string& imageName) {
  int dl[3], di[3];
  double ol[3], oi[3], sl[3], si[3];
  labels->GetDimensions(dl);
  image->GetDimensions(di);
  labels->GetOrigin(ol);
  image->GetOrigin(oi);
  labels->GetSpacing(sl);
  image->GetSpacing(si);
  bool same = dl[0] == di[0] && dl[1] == di[1] && dl[2] == di[2];
  for (int a = 0; a < 3 && same; ++a)
    same = std::fabs(ol[a] - oi[a]) <= 1e-4 * std::max(1.0, std::fabs(sl[a])) &&
           std::fabs(sl[a] - si[a]) <= 1e-6 * std::fabs(sl[a]);
  for (int r = 0; r < 3 && same; ++r)
    for (int c = 0; c < 3 && same; ++c)
      same = std::fabs(labels->GetDirectionMatrix()->GetElement(r, c) -
                       image->GetDirectionMatrix()->GetElement(r, c)) <= 1e-6;
  if (!same)
    throw std::runtime_error(imageName + " and " + labelsName + " are on different grids (" +
                             describeGrid(image) + " vs " + describeGrid(labels) + ")");
}

}  // namespace repose
