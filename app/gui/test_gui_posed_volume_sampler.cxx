// The slice views' posed volumes (PosedVolumeSampler) on the real TotalSegmentator case: every voxel
// as the pipeline's own posed labels and CT, pose after pose with one sampler (its caches kept),
// earlier results untouched by later poses, the rest volumes for the rest pose, and two threads
// asking at once. No display needed.
#include <QtTest>
#include <thread>

#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkUnstructuredGrid.h>

#include "posed_volume_sampler.h"
#include "repose_pipeline.h"

using namespace repose;

namespace {

/// Same lattice and every voxel equal.
bool sameImage(vtkImageData* a, vtkImageData* b) {
  if (!a || !b) return a == b;
  int ea[6], eb[6];
  a->GetExtent(ea);
  b->GetExtent(eb);
  for (int i = 0; i < 6; ++i)
    if (ea[i] != eb[i]) return false;
  for (int i = 0; i < 3; ++i)
    if (a->GetOrigin()[i] != b->GetOrigin()[i] || a->GetSpacing()[i] != b->GetSpacing()[i]) return false;
  vtkDataArray* sa = a->GetPointData()->GetScalars();
  vtkDataArray* sb = b->GetPointData()->GetScalars();
  if (!sa || !sb || sa->GetNumberOfTuples() != sb->GetNumberOfTuples()) return false;
  for (vtkIdType i = 0; i < sa->GetNumberOfTuples(); ++i)
    if (sa->GetTuple1(i) != sb->GetTuple1(i)) return false;
  return true;
}

vtkSmartPointer<vtkImageData> deepCopy(vtkImageData* image) {
  auto copy = vtkSmartPointer<vtkImageData>::New();
  copy->DeepCopy(image);
  return copy;
}

vtkSmartPointer<vtkPoints> nodesOf(Pipeline& pipeline) {
  auto points = vtkSmartPointer<vtkPoints>::New();
  points->DeepCopy(pipeline.posedMesh()->GetPoints());
  return points;
}

std::string hipPose(double degrees) {
  return "{\"rotations\": {\"left_hip\": {\"axis\": [1, 0, 0], \"degrees\": " + std::to_string(-degrees) +
         "}, \"right_hip\": {\"axis\": [0, 1, 0], \"degrees\": " + std::to_string(degrees / 2) + "}}}";
}

}  // namespace

class PosedVolumeSamplerTest : public QObject {
  Q_OBJECT
 private slots:
  void matchesThePipelinePoseAfterPose() {
    const std::string caseDir = REPOSE_GUI_TOTALSEG_CASE;
    if (!QFileInfo::exists(QString::fromStdString(caseDir + "/manifest.json")))
      QSKIP("the TotalSegmentator case was not prepared (no shared data)");
    Pipeline pipeline;
    pipeline.loadCase(caseDir);
    pipeline.setRestImage(readIntensityImage(std::string(REPOSE_SHARED_DATA) + "/totalsegmentator/example_ct.nii.gz"),
                          "example_ct.nii.gz");
    PosedVolumeSampler sampler(pipeline.restLabels(), pipeline.restImage(), pipeline.restMesh());

    const PosedVolumeSampler::Volumes rest = sampler.sample(nullptr);
    QVERIFY(sameImage(rest.labels, pipeline.restLabels()));
    QVERIFY(sameImage(rest.image, pipeline.restImage()));

    std::vector<vtkSmartPointer<vtkImageData>> shown, expected;
    for (double degrees : {30.0, 60.0}) {
      pipeline.setPose(hipPose(degrees), "hip pose");
      const PosedVolumeSampler::Volumes v = sampler.sample(nodesOf(pipeline));
      QVERIFY2(sameImage(v.labels, pipeline.posedLabels()), "posed labels differ from the pipeline's");
      QVERIFY2(sameImage(v.image, pipeline.posedImage()), "posed CT differs from the pipeline's");
      shown.push_back(v.labels);
      expected.push_back(deepCopy(pipeline.posedLabels()));
    }
    // The first pose's volume, still held by a view, is not overwritten by the second pose.
    QVERIFY(sameImage(shown[0], expected[0]));
    QVERIFY(!sameImage(shown[0], shown[1]));

    // Two threads at once: one resample at a time, each gets the volume of its own nodes.
    vtkSmartPointer<vtkPoints> second = nodesOf(pipeline);
    pipeline.setPose(hipPose(30.0), "hip pose");
    vtkSmartPointer<vtkPoints> first = nodesOf(pipeline);
    PosedVolumeSampler::Volumes a, b;
    std::thread ta([&] { a = sampler.sample(first); });
    std::thread tb([&] { b = sampler.sample(second); });
    ta.join();
    tb.join();
    QVERIFY(sameImage(a.labels, expected[0]));
    QVERIFY(sameImage(b.labels, expected[1]));
  }
};

QTEST_GUILESS_MAIN(PosedVolumeSamplerTest)
#include "test_gui_posed_volume_sampler.moc"
