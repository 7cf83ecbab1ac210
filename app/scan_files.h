#pragma once
// The app's scan and mesh files: label volumes and CT images in (NIfTI, NRRD, MetaImage, a DICOM
// series folder), images, meshes and surfaces out, each error one line naming the file.
#include <string>

#include <vtkImageData.h>
#include <vtkSmartPointer.h>

class vtkPolyData;
class vtkUnstructuredGrid;

namespace repose {

/// Largest label value accepted: label-indexed tables stay small whatever a damaged file claims.
constexpr int kMaxLabelValue = 1000000;

/// Reads a label volume; float files holding whole numbers are accepted. Throws std::runtime_error
/// "FILE: problem" (unreadable, not integer, negative or above kMaxLabelValue, empty).
vtkSmartPointer<vtkImageData> readLabelVolume(const std::string& path);
/// Reads an intensity image (CT/MRI) as float.
vtkSmartPointer<vtkImageData> readIntensityImage(const std::string& path, const std::string& seriesUid = "");
/// Writes an image, format from the extension; throws std::runtime_error naming the file.
void writeImage(vtkImageData* image, const std::string& path);
/// writeImage for label volumes: written in the smallest integer type that holds the labels
/// (vtkReposeImageWriter::SmallestIntegerType), e.g. unsigned char for up to 255.
void writeLabelImage(vtkImageData* labels, const std::string& path);
void writeMesh(vtkUnstructuredGrid* mesh, const std::string& path);
void writeSurfaces(vtkPolyData* surfaces, const std::string& path);
/// Throws std::runtime_error "LABEL_FILE and IMAGE_FILE are on different grids (...)".
void checkSameGrid(vtkImageData* labels, const std::string& labelsName, vtkImageData* image,
                   const std::string& imageName);
/// "DxDxD voxels of SxSxS mm at (x, y, z)", for messages about grids.
std::string describeGrid(vtkImageData* image);

}  // namespace repose
