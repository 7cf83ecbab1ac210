#include "fidelity_plot.h"
#include "checked_write.h"

#include <stdexcept>

#include <vtkAxis.h>
#include <vtkChartLegend.h>
#include <vtkChartXY.h>
#include <vtkContextScene.h>
#include <vtkContextView.h>
#include <vtkDoubleArray.h>
#include <vtkNew.h>
#include <vtkPNGWriter.h>
#include <vtkPen.h>
#include <vtkPlot.h>
#include <vtkRenderWindow.h>
#include <vtkRenderer.h>
#include <vtkTable.h>
#include <vtkTextProperty.h>
#include <vtkWindowToImageFilter.h>

namespace repose {

void plotVolumeRatios(const std::map<std::string, std::vector<std::pair<double, double>>>& series,
                      const std::string& pngPath, int width, int height) {
  vtkNew<vtkContextView> view;
  view->GetRenderer()->SetBackground(1, 1, 1);
  view->GetRenderWindow()->SetOffScreenRendering(1);
  view->GetRenderWindow()->SetSize(width, height);
  vtkNew<vtkChartXY> chart;
  view->GetScene()->AddItem(chart);
  chart->SetShowLegend(true);
  chart->SetTitle("Body volume ratio (posed tet mesh / rest)");
  chart->GetAxis(vtkAxis::BOTTOM)->SetTitle("frame");
  chart->GetAxis(vtkAxis::LEFT)->SetTitle("volume ratio");
  const unsigned char colours[4][3] = {{200, 60, 50}, {40, 110, 200}, {30, 150, 70}, {120, 80, 160}};
  int index = 0;
  for (const auto& [method, points] : series) {
    vtkNew<vtkTable> table;
    vtkNew<vtkDoubleArray> x, y;
    x->SetName("frame");
    y->SetName(method.c_str());
    for (const auto& [f, r] : points) {
      x->InsertNextValue(f);
      y->InsertNextValue(r);
    }
    table->AddColumn(x);
    table->AddColumn(y);
    vtkPlot* plot = chart->AddPlot(points.size() > 1 ? vtkChart::LINE : vtkChart::POINTS);
    plot->SetInputData(table, 0, 1);
    const unsigned char* c = colours[index++ % 4];
    plot->SetColor(c[0], c[1], c[2], 255);
    plot->SetWidth(2.0);
  }
  view->GetRenderWindow()->Render();
  vtkNew<vtkWindowToImageFilter> grab;
  grab->SetInput(view->GetRenderWindow());
  grab->Update();
  vtkNew<vtkPNGWriter> writer;
  writer->SetFileName(pngPath.c_str());
  writer->SetInputConnection(grab->GetOutputPort());
  writeChecked(writer.Get(), pngPath, kPngTail);
}

}  // namespace repose
