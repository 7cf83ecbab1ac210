#pragma once
// Posed label and CT volumes for views that refresh off the UI thread (the GUI's slice views).
//
// A sampler holds its own shallow copies of a case's rest labels, rest image and rest mesh and one
// vtkReposePosedVolume per volume, kept for the case's lifetime: the rest-side work (the tets and
// nodes converted, the rest volume's scalars, the mesh's boundary, its coverage of the rest grid and
// the distance to it) is done on the first pose and reused by every later one, where a filter built
// per pose redid it each time. Only the pose's node coordinates travel to the worker thread.
#include <memory>
#include <mutex>

#include <vtkSmartPointer.h>

class vtkImageData;
class vtkPoints;
class vtkReposePosedVolume;
class vtkUnstructuredGrid;

namespace repose {

class PosedVolumeSampler {
 public:
  /// `restLabels` and `restMesh` are required; `restImage` may be null (no CT). The sampler keeps
  /// shallow copies, so the caller's objects may change afterwards without affecting it.
  PosedVolumeSampler(vtkImageData* restLabels, vtkImageData* restImage, vtkUnstructuredGrid* restMesh);
  ~PosedVolumeSampler();
  PosedVolumeSampler(const PosedVolumeSampler&) = delete;
  PosedVolumeSampler& operator=(const PosedVolumeSampler&) = delete;

  struct Volumes {
    vtkSmartPointer<vtkImageData> labels;  ///< nearest-neighbour labels, background 0
    vtkSmartPointer<vtkImageData> image;   ///< trilinear CT, background its minimum; null without a CT
  };
  /// The volumes posed by `posedNodes` (the rest mesh's nodes moved, same order; the caller's copy,
  /// not modified), or the rest volumes for null. Thread-safe: one call runs at a time. The returned
  /// images are the caller's; a later call does not change them. Throws std::runtime_error.
  Volumes sample(vtkPoints* posedNodes);
  /// Does the rest-side work now (a resample through the rest pose), so that the first posed sample
  /// takes as long as every later one. Meant for a background thread right after a case opens.
  void warmUp();

 private:
  std::mutex mutex_;
  vtkSmartPointer<vtkImageData> labels_, image_;
  vtkSmartPointer<vtkUnstructuredGrid> restMesh_, posedMesh_;
  vtkSmartPointer<vtkReposePosedVolume> labelResampler_, imageResampler_;
};

}  // namespace repose
