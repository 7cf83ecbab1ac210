// repose-gui: the Repose desktop application.
//   repose-gui [CASE_DIR [--image CT]]            open a prepared case (and its CT) at start
//   repose-gui --benchmark-drag CASE_DIR [--frames N] [--joint NAME]
//       opens the case, drags a joint N times through the same code path as a mouse drag
//       (pose, skin, deform surfaces, render) and prints the frame times.
#include <algorithm>
#include <ctime>
#include <cstring>
#include <iostream>
#include <numeric>
#include <string>
#include <vector>

#include <QApplication>
#include <QElapsedTimer>
#include <QPixmap>
#include <QTimer>
#include <QSurfaceFormat>
#include <QVTKOpenGLNativeWidget.h>
#include <vtkLogger.h>
#include <vtkNew.h>
#include <vtkOpenGLRenderWindow.h>
#include <vtkOutputWindow.h>
#include <vtkPolyData.h>
#include <vtkUnstructuredGrid.h>

#include "main_window.h"
#include "repose_pipeline.h"
#include "repose_version.h"
#include "scene_view.h"

namespace {

/// VTK's console messages only with REPOSE_VERBOSE; the user sees errors as dialogs.
class QuietOutputWindow : public vtkOutputWindow {
public:
  static QuietOutputWindow* New() { return new QuietOutputWindow; }
  void DisplayText(const char* text) override {
    if (std::getenv("REPOSE_VERBOSE")) std::cerr << text;
  }
};

bool waitFor(const std::function<bool()>& done, int timeoutMs) {
  QElapsedTimer clock;
  clock.start();
  while (!done()) {
    if (clock.elapsed() > timeoutMs) return false;
    QApplication::processEvents(QEventLoop::AllEvents, 50);
  }
  return true;
}

int benchmarkDrag(repose::MainWindow& window, const QString& caseDir, int frames, const std::string& jointName) {
  QString failure;
  window.setErrorHandler([&](const QString& m) { failure = m; });
  window.openCase(caseDir);
  if (!waitFor([&] { return !window.isOpening(); }, 600000) || !window.hasCase()) {
    std::cerr << "repose-gui: error: " << (failure.isEmpty() ? "cannot open " + caseDir : failure).toStdString() << "\n";
    return 1;
  }
  QApplication::processEvents();
  const repose::Skeleton& skeleton = window.controller()->skeleton();
  int joint = skeleton.find(jointName);
  if (joint < 0) joint = skeleton.size() > 1 ? 1 : 0;
  window.scene()->setSelectedJoint(joint);
  window.controller()->beginEdit();
  std::vector<double> times, skin, surf, render;
  // CPU time of all threads (software OpenGL renders on every core): the frame cost without the
  // other processes that share the machine.
  const std::clock_t cpu0 = std::clock();
  for (int i = 0; i < frames; ++i) {
    // Back and forth so the joint stays inside its limits: 40 frames each way.
    const double dx = ((i / 40) % 2 == 0) ? 3.0 : -3.0;
    times.push_back(window.simulateDrag(dx, 1.0 * (((i / 20) % 2) ? 1 : -1)));
    skin.push_back(window.lastFrameTiming().skinning);
    surf.push_back(window.lastFrameTiming().surfaces);
    render.push_back(window.lastFrameTiming().render);
    QApplication::processEvents();
  }
  const double cpuPerFrame = double(std::clock() - cpu0) / CLOCKS_PER_SEC / frames;
  window.controller()->endEdit();
  // Full detail, as shown once the drag is released.
  std::vector<double> full;
  for (int i = 0; i < 10; ++i) {
    full.push_back(window.simulateDrag(i % 2 ? 2.0 : -2.0, 0));
    QApplication::processEvents();
  }
  auto mean = [](const std::vector<double>& v) { return std::accumulate(v.begin(), v.end(), 0.0) / v.size(); };
  std::vector<double> sorted = times;
  std::sort(sorted.begin(), sorted.end());
  const double p95 = sorted[std::min(sorted.size() - 1, std::size_t(0.95 * sorted.size()))];
  repose::Pipeline* p = window.pipeline();
  std::printf("drag benchmark: %s, joint '%s', %d frames, %lld tet nodes, %lld tets, %lld surface vertices\n",
              caseDir.toUtf8().constData(), skeleton.joints[std::size_t(joint)].name.c_str(), frames,
              (long long)p->restMesh()->GetNumberOfPoints(), (long long)p->restMesh()->GetNumberOfCells(),
              (long long)p->restSurfaces()->GetNumberOfPoints());
  std::printf("  %-22s %10s\n", "stage", "mean ms");
  std::printf("  %-22s %10.2f\n", "skinning", 1e3 * mean(skin));
  std::printf("  %-22s %10.2f\n", "surface deformation", 1e3 * mean(surf));
  std::printf("  %-22s %10.2f\n", "render", 1e3 * mean(render));
  std::printf("  %-22s %10.2f\n", "frame (mean)", 1e3 * mean(times));
  std::printf("  %-22s %10.2f\n", "frame (95th pct)", 1e3 * p95);
  std::printf("  %-22s %10.1f\n", "frames per second", 1.0 / mean(times));
  std::printf("  %-22s %10.2f\n", "CPU ms per frame", 1e3 * cpuPerFrame);
  std::printf("  drawn while dragging: %lld triangles (full detail %lld); full-detail frame after release %.1f ms\n",
              (long long)(window.scene()->interactiveTriangles() ? window.scene()->interactiveTriangles()
                                                                 : p->restSurfaces()->GetNumberOfPolys()),
              (long long)p->restSurfaces()->GetNumberOfPolys(), 1e3 * mean(full));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  vtkNew<QuietOutputWindow> quiet;
  vtkOutputWindow::SetInstance(quiet);
  if (!std::getenv("REPOSE_VERBOSE")) vtkLogger::SetStderrVerbosity(vtkLogger::VERBOSITY_OFF);
  QString benchmarkCase, openDir, grabFile, imageFile;
  int frames = 200;
  std::string jointName = "left_hip";
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--help" || a == "-h") {
      std::cout << "usage: repose-gui [CASE_DIR [--image CT]]\n"
                   "       repose-gui --benchmark-drag CASE_DIR [--frames N] [--joint NAME]\n"
                   "       repose-gui CASE_DIR --grab FILE.png\n"
                   "       repose-gui --version\n"
                   "  Opens the Repose desktop application (optionally with a prepared case).\n"
                   "  --benchmark-drag  drag a joint N times (default 200) as the mouse does and print frame times\n"
                   "  --image CT        the case's CT (on its label grid), shown in the slice views\n"
                   "  --grab FILE.png   save a picture of the whole window once the case is shown, then quit\n";
      return 0;
    }
    if (a == "--version") return std::cout << "repose-gui " << REPOSE_VERSION << "\n", 0;
    if (a == "--benchmark-drag" && i + 1 < argc) benchmarkCase = argv[++i];
    else if (a == "--frames" && i + 1 < argc) frames = std::max(1, std::atoi(argv[++i]));
    else if (a == "--joint" && i + 1 < argc) jointName = argv[++i];
    else if (a == "--grab" && i + 1 < argc) grabFile = argv[++i];
    else if (a == "--image" && i + 1 < argc) imageFile = argv[++i];
    else if (!a.empty() && a[0] != '-') openDir = QString::fromStdString(a);
  }
  vtkOpenGLRenderWindow::SetGlobalMaximumNumberOfMultiSamples(0);
  QSurfaceFormat::setDefaultFormat(QVTKOpenGLNativeWidget::defaultFormat());
  QApplication app(argc, argv);
  QApplication::setApplicationName("Repose");
  repose::MainWindow window;
  window.show();
  if (!benchmarkCase.isEmpty()) return benchmarkDrag(window, benchmarkCase, frames, jointName);
  if (!openDir.isEmpty()) window.openCase(openDir);
  if (!imageFile.isEmpty())
    QObject::connect(&window, &repose::MainWindow::caseOpened, &window, [&] { window.loadRestImage(imageFile); });
  QElapsedTimer clock;
  clock.start();
  if (!grabFile.isEmpty()) {
    // For documentation: the window as a user sees it, once the case is open and the slice views are
    // filled (or opening failed: the start page with its message).
    auto* poll = new QTimer(&window);
    QObject::connect(poll, &QTimer::timeout, &window, [&, poll] {
      const bool busy = window.isOpening() || (window.hasCase() && window.slicesPending());
      if (busy && clock.elapsed() < 600000) return;
      poll->stop();
      QApplication::processEvents();
      const bool ok = window.grab().save(grabFile);
      if (!ok) std::cerr << "repose-gui: error: " << grabFile.toStdString() << ": cannot write the picture\n";
      app.exit(ok ? 0 : 1);
    });
    poll->start(500);
  }
  return app.exec();
}
