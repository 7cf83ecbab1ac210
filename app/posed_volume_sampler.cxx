#include "posed_volume_sampler.h"

#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkUnstructuredGrid.h>

#include "repose_pipeline.h"
#include "vtkReposePosedVolume.h"

namespace repose {

namespace {
vtkSmartPointer<vtkImageData> ownCopy(vtkImageData* image) {
  auto out = vtkSmartPointer<vtkImageData>::New();
  out->ShallowCopy(image);
  return out;
}
}  // namespace

PosedVolumeSampler::PosedVolumeSampler(vtkImageData* restLabels, vtkImageData* restImage,
                                       vtkUnstructuredGrid* restMesh) {
  if (!restLabels || !restMesh) throw std::runtime_error("posed volumes: no case loaded");
  labels_ = ownCopy(restLabels);
  restMesh_ = vtkSmartPointer<vtkUnstructuredGrid>::New();
  restMesh_->ShallowCopy(restMesh);
  posedMesh_ = vtkSmartPointer<vtkUnstructuredGrid>::New();
  posedMesh_->ShallowCopy(restMesh);
  labelResampler_ = vtkSmartPointer<vtkReposePosedVolume>::New();
  labelResampler_->SetInputData(0, labels_);
  labelResampler_->SetRestMeshData(restMesh_);
  labelResampler_->SetPosedMeshData(posedMesh_);
  labelResampler_->SetInterpolationToNearest();
  labelResampler_->SetBackgroundValue(0);
  if (restImage) {
    image_ = ownCopy(restImage);
    double range[2] = {0, 0};
    image_->GetPointData()->GetScalars()->GetRange(range);
    imageResampler_ = vtkSmartPointer<vtkReposePosedVolume>::New();
    imageResampler_->SetInputData(0, image_);
    imageResampler_->SetRestMeshData(restMesh_);
    imageResampler_->SetPosedMeshData(posedMesh_);
    imageResampler_->SetInterpolationToLinear();
    imageResampler_->SetBackgroundValue(range[0]);
  }
}

PosedVolumeSampler::~PosedVolumeSampler() = default;

PosedVolumeSampler::Volumes PosedVolumeSampler::sample(vtkPoints* posedNodes) {
  std::lock_guard<std::mutex> lock(mutex_);
  Volumes v;
  if (!posedNodes) {
    v.labels = ownCopy(labels_);
    if (image_) v.image = ownCopy(image_);
    return v;
  }
  if (posedNodes->GetNumberOfPoints() != restMesh_->GetNumberOfPoints())
    throw std::runtime_error("posed volumes: the posed nodes do not match the case's mesh");
  posedMesh_->SetPoints(posedNodes);
  updateOrThrow(labelResampler_, "posed volume for the slice views");
  v.labels = ownCopy(labelResampler_->GetOutput());
  if (imageResampler_) {
    updateOrThrow(imageResampler_, "posed volume for the slice views");
    v.image = ownCopy(imageResampler_->GetOutput());
  }
  return v;
}

void PosedVolumeSampler::warmUp() {
  auto restNodes = vtkSmartPointer<vtkPoints>::New();
  restNodes->DeepCopy(restMesh_->GetPoints());
  sample(restNodes);
}

}  // namespace repose
