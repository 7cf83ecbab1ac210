// The drag preview's decimation: two spheres 5 mm apart share grid cells, yet no coarse triangle
// joins them, and moving one sphere stretches no coarse edge (cell-only clustering, as
// vtkQuadricClustering does, made 38 triangles across the gap here, stretched 32-fold). No display.
#include <QtTest>
#include <vtkAppendPolyData.h>
#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkIdList.h>
#include <vtkIntArray.h>
#include <vtkMath.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSphereSource.h>

#include "surface_lod.h"

using namespace repose;

class TestSurfaceLod : public QObject {
  Q_OBJECT
private slots:
  void separatePartsStaySeparate() {
    // Sphere A (label 1) at x = 0 and sphere B (label 2) at x = 105, radius 50: a 5 mm gap. With 15
    // cells along x (13.7 mm each) the gap lies inside one column of cells.
    vtkNew<vtkAppendPolyData> both;
    for (int s = 0; s < 2; ++s) {
      vtkNew<vtkSphereSource> sphere;
      sphere->SetRadius(50);
      sphere->SetCenter(105.0 * s, 0, 0);
      sphere->SetThetaResolution(80);
      sphere->SetPhiResolution(80);
      sphere->Update();
      auto part = vtkSmartPointer<vtkPolyData>::New();
      part->DeepCopy(sphere->GetOutput());
      vtkNew<vtkIntArray> label;
      label->SetName("Label");
      for (vtkIdType c = 0; c < part->GetNumberOfCells(); ++c) label->InsertNextValue(s + 1);
      part->GetCellData()->SetScalars(label);
      both->AddInputData(part);
    }
    both->Update();
    vtkPolyData* full = both->GetOutput();
    const vtkIdType firstOfB = full->GetNumberOfPoints() / 2;
    std::vector<vtkIdType> ids;
    auto coarse = decimateKeepingVertices(full, 15, ids);
    QVERIFY(coarse->GetNumberOfPolys() > 400);
    QVERIFY(coarse->GetNumberOfPolys() < full->GetNumberOfPolys() / 4);
    QCOMPARE(vtkIdType(ids.size()), coarse->GetNumberOfPoints());
    // Every coarse vertex is a full vertex at the same place.
    for (std::size_t i = 0; i < ids.size(); ++i) {
      double a[3], b[3];
      coarse->GetPoint(vtkIdType(i), a);
      full->GetPoint(ids[i], b);
      QCOMPARE(vtkMath::Distance2BetweenPoints(a, b), 0.0);
    }
    // No triangle has corners on both spheres, and each keeps its sphere's label.
    vtkDataArray* labels = coarse->GetCellData()->GetScalars();
    QVERIFY(labels);
    auto corners = vtkSmartPointer<vtkIdList>::New();
    vtkIdType c = 0;
    for (coarse->GetPolys()->InitTraversal(); coarse->GetPolys()->GetNextCell(corners); ++c) {
      int onB = 0;
      for (vtkIdType k = 0; k < 3; ++k) onB += ids[std::size_t(corners->GetId(k))] >= firstOfB;
      QVERIFY2(onB == 0 || onB == 3, "a coarse triangle spans the gap between the spheres");
      QCOMPARE(int(labels->GetTuple1(c)), onB ? 2 : 1);
    }
  }
};

QTEST_GUILESS_MAIN(TestSurfaceLod)
#include "test_gui_surface_lod.moc"
