// MainWindow, continued: pose files, the CT, exports and motion clips. Every output is written
// through a temporary name and moved into place when complete; errors become the one-line dialog.
#include <cstdio>
#include <filesystem>

#include <QApplication>
#include <QProgressDialog>
#include <QStatusBar>

#include "animation_panel.h"
#include "atomic_outputs.h"
#include "label_export.h"
#include "main_window.h"
#include "pvd_series.h"
#include "repose_pipeline.h"
#include "scene_view.h"

namespace repose {
namespace {

/// Writes one file through a temporary name in its folder, moved into place when complete.
void writeAtomically(const QString& path, const std::function<void(const std::string&)>& write) {
  const std::filesystem::path p(path.toStdString());
  AtomicOutputs out(p.has_parent_path() ? p.parent_path().string() : ".");
  write(out.stage(p.filename().string()));
  out.commit();
}

}  // namespace

// --- files -----------------------------------------------------------------------------------

bool MainWindow::savePose(const QString& path) {
  return guarded([&] {
    if (!pipeline_) throw std::runtime_error("no case open");
    // Axis and degrees per joint: a file a person can read and edit.
    writeAtomically(path, [&](const std::string& tmp) { writeTextFile(tmp, poseToAxisAngleJson(controller_.pose())); });
    controller_.markSaved();
    statusBar()->showMessage("Pose saved to " + path, 5000);
  });
}

bool MainWindow::loadPose(const QString& path) {
  return guarded([&] {
    if (!pipeline_) throw std::runtime_error("no case open");
    const std::string p = path.toStdString();
    Pose pose;
    try {
      pose = parsePoseJson(readTextFile(p));
      validatePose(pose, controller_.skeleton());
    } catch (const std::invalid_argument& e) {
      throw std::runtime_error(p + ": " + e.what());
    }
    animation_->pause();
    controller_.setPose(pose);
    controller_.markSaved();
  });
}

bool MainWindow::loadRestImage(const QString& path) {
  return guarded([&] {
    if (!pipeline_) throw std::runtime_error("no case open");
    auto image = readIntensityImage(path.toStdString());
    pipeline_->setRestImage(image, path.toStdString());
    sliceWatcher_.waitForFinished();
    restImage_ = image;
    newSliceSampler();  // the slice updates sample the new image
    updateActions();
    requestSliceUpdate();
  });
}

bool MainWindow::exportPosedLabels(const QString& path) {
  return guarded([&] {
    if (!pipeline_) throw std::runtime_error("no case open");
    QApplication::setOverrideCursor(Qt::WaitCursor);
    // The label names beside the volume (posed_labels.tsv), written with it or not at all.
    const std::filesystem::path p(path.toStdString());
    AtomicOutputs out(p.has_parent_path() ? p.parent_path().string() : ".");
    writeLabelImage(pipeline_->posedLabels(), out.stage(p.filename().string()));
    if (!table_.labels.empty())
      writeTextFile(out.stage(std::filesystem::path(labelTablePathFor(p.filename().string())).string()),
                    labelTableToTsv(table_));
    out.commit();
    QApplication::restoreOverrideCursor();
    statusBar()->showMessage("Posed label volume written to " + path, 5000);
  });
}

bool MainWindow::exportPosedImage(const QString& path) {
  return guarded([&] {
    if (!pipeline_) throw std::runtime_error("no case open");
    if (!restImage_) throw std::runtime_error("no CT for this case (File > Load CT for this case)");
    QApplication::setOverrideCursor(Qt::WaitCursor);
    writeAtomically(path, [&](const std::string& tmp) { writeImage(pipeline_->posedImage(), tmp); });
    QApplication::restoreOverrideCursor();
    statusBar()->showMessage("Posed CT written to " + path, 5000);
  });
}

bool MainWindow::exportPosedMesh(const QString& path) {
  return guarded([&] {
    if (!pipeline_) throw std::runtime_error("no case open");
    writeAtomically(path, [&](const std::string& tmp) { writeMesh(withLabelNames(pipeline_->posedMesh(), table_), tmp); });
    statusBar()->showMessage("Posed mesh written to " + path, 5000);
  });
}

bool MainWindow::exportPosedSurfaces(const QString& path) {
  return guarded([&] {
    if (!pipeline_) throw std::runtime_error("no case open");
    writeAtomically(path, [&](const std::string& tmp) { writeSurfaces(withLabelNames(pipeline_->posedSurfaces(), table_), tmp); });
    statusBar()->showMessage("Posed surfaces written to " + path, 5000);
  });
}

bool MainWindow::exportScreenshot(const QString& path) {
  return guarded([&] {
    writeAtomically(path, [&](const std::string& tmp) { scene_->saveScreenshot(tmp); });
    statusBar()->showMessage("Screenshot written to " + path, 5000);
  });
}

bool MainWindow::loadClip(const QString& bvhPath, const QString& mapPath) {
  if (pipeline_ && controller_.isHandPose() &&
      ask("The clip's frames replace the pose you made (Edit > Undo brings it back). Load the clip?",
          QMessageBox::Yes | QMessageBox::No, QMessageBox::No) != QMessageBox::Yes)
    return false;
  return guarded([&] {
    if (!pipeline_) throw std::runtime_error("no case open");
    animation_->loadClip(bvhPath, mapPath);
    updateActions();
  });
}

bool MainWindow::exportAnimation(const QString& dir, int step, int first, int last) {
  if (exporting_) return false;
  return guarded([&] {
    if (!pipeline_) throw std::runtime_error("no case open");
    if (!animation_->hasClip()) throw std::runtime_error("no motion loaded (Motion > Load motion)");
    animation_->pause();
    const int frames = animation_->frameCount();
    step = std::max(1, step);
    first = std::clamp(first, 0, frames - 1);
    last = last < 0 ? frames - 1 : std::clamp(last, first, frames - 1);
    // The progress dialog processes events: a close or a new case waits for this loop (they ask it
    // to stop), and the pipeline is held here meanwhile.
    std::shared_ptr<Pipeline> p = pipeline_;
    const AnimationPanel* clip = animation_;
    exporting_ = true;
    abortExport_ = false;
    struct Done {
      bool& flag;
      ~Done() { flag = false; }
    } done{exporting_};
    QProgressDialog progress("Writing the animation series…", "Cancel", first, last + 1, this);
    progress.setWindowModality(Qt::WindowModal);
    progress.setMinimumDuration(500);
    AtomicOutputs out(dir.toStdString());
    makeDirectories(out.stage("frames"));
    std::vector<PvdEntry> entries;
    bool cancelled = false;
    try {
      for (int f = first; f <= last; f += step) {
        progress.setValue(f);
        if (progress.wasCanceled() || abortExport_) {
          cancelled = true;
          break;
        }
        p->setPose(clip->pose(f));
        const double time = f * clip->frameTime();
        char name[64];
        std::snprintf(name, sizeof(name), "frames/mesh_%05d.vtu", f);
        writeMesh(withLabelNames(p->posedMesh(), table_), out.stage(name));
        entries.push_back({time, 0, name});
        std::snprintf(name, sizeof(name), "frames/surfaces_%05d.vtp", f);
        writeSurfaces(withLabelNames(p->posedSurfaces(), table_), out.stage(name));
        entries.push_back({time, 1, name});
      }
    } catch (...) {
      p->setPose(controller_.pose());
      throw;
    }
    p->setPose(controller_.pose());
    progress.setValue(last + 1);
    if (cancelled) return;  // the temporary folder is removed
    writeTextFile(out.stage("animation.pvd"), pvdText(entries));
    if (!table_.labels.empty()) writeTextFile(out.stage("labels.tsv"), labelTableToTsv(table_));
    out.commit();
    statusBar()->showMessage(QString("%1 frames written to %2/animation.pvd").arg(entries.size() / 2).arg(dir), 8000);
  });
}

}  // namespace repose
