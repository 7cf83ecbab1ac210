#include "preprocess_worker.h"

#include <QDir>
#include <QFileInfo>
#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkPointData.h>

#include "atomic_outputs.h"
#include "vtkReposeAutoRig.h"
#include "vtkReposePhantomSource.h"

namespace repose {

LabelTable findCaseLabelTable(const std::string& caseDir) {
  const QDir dir(QString::fromStdString(caseDir));
  for (const QString& candidate : {dir.filePath("labels.tsv"), dir.filePath("../labels.tsv")})
    if (QFileInfo::exists(candidate)) {
      try {
        return readLabelTableFile(candidate.toStdString());
      } catch (const std::exception&) {
        // A broken optional table only costs the names.
      }
    }
  return LabelTable();
}

PreprocessWorker::PreprocessWorker(const OpenRequest& request, QObject* parent)
    : QThread(parent), request_(request) {}

void PreprocessWorker::run() {
  try {
    open();
  } catch (const Cancelled&) {
    cancelled_ = true;
  } catch (const std::exception& e) {
    error_ = QString::fromStdString(e.what()).replace('\n', ' ');
  } catch (...) {
    error_ = "unexpected error while opening";
  }
}

void PreprocessWorker::open() {
  auto pipeline = std::make_shared<Pipeline>();
  const bool save = !request_.saveCaseDir.isEmpty();
  auto stage = [this](const QString& text) {
    if (cancelled_) throw Cancelled();
    emit progress(step_++, steps_, text);
  };
  pipeline->setProgress([&](const std::string& s) { stage(QString::fromStdString(s)); });
  pipeline->setCancelCheck([this] { return bool(cancelled_); });
  const std::string labelsExt = ".nii.gz";

  if (request_.kind == OpenRequest::Case) {
    steps_ = 1;
    stage("reading the prepared case");
    const std::string dir = request_.caseDir.toStdString();
    pipeline->loadCase(dir);
    result_.table = findCaseLabelTable(dir);
    result_.title = QFileInfo(request_.caseDir).fileName();
  } else if (request_.kind == OpenRequest::Phantom) {
    steps_ = 5 + (save ? 1 : 0);
    stage("building the " + request_.phantomSize + " phantom");
    auto phantom = vtkSmartPointer<vtkReposePhantomSource>::New();
    phantom->SetSizeName(request_.phantomSize.toUtf8().constData());
    phantom->Update();
    vtkImageData* labels = phantom->GetOutput();
    if (!labels || !labels->GetPointData()->GetScalars())
      throw std::runtime_error("phantom: cannot build the " + request_.phantomSize.toStdString() + " phantom");
    auto copy = vtkSmartPointer<vtkImageData>::New();
    copy->ShallowCopy(labels);
    result_.table = parseLabelTable(phantom->GetLabelTableTSV(), "phantom label table");
    pipeline->prepare(copy, "phantom", phantom->GetSkeletonJSON(), "phantom skeleton", nullptr, "", request_.settings);
    result_.title = "Phantom (" + request_.phantomSize + ")";
  } else {
    const std::string labelsPath = request_.labelsPath.toStdString();
    steps_ = 5 + (request_.autoSkeleton ? 1 : 0) + (save ? 1 : 0);
    stage("reading " + QFileInfo(request_.labelsPath).fileName());
    vtkSmartPointer<vtkImageData> labels = readLabelVolume(labelsPath);
    vtkSmartPointer<vtkImageData> image;
    if (!request_.imagePath.isEmpty()) {
      image = readIntensityImage(request_.imagePath.toStdString());
      checkSameGrid(labels, labelsPath, image, request_.imagePath.toStdString());
    }
    std::string tableTsv;
    if (!request_.labelTablePath.isEmpty()) {
      tableTsv = readTextFile(request_.labelTablePath.toStdString());
      try {
        result_.table = parseLabelTable(tableTsv, request_.labelTablePath.toStdString());
      } catch (const std::invalid_argument& e) {
        throw std::runtime_error(e.what());
      }
    }
    std::string skeletonJson, skeletonName;
    if (request_.autoSkeleton) {
      stage("finding the skeleton from the bone labels");
      auto rig = vtkSmartPointer<vtkReposeAutoRig>::New();
      rig->SetInputData(labels);
      if (!tableTsv.empty()) rig->SetLabelTableTSV(tableTsv.c_str());
      updateOrThrow(rig, "automatic skeleton of " + labelsPath);
      if (rig->GetNumberOfJoints() < 2)
        throw std::runtime_error(labelsPath + ": the automatic skeleton found " + std::to_string(rig->GetNumberOfJoints()) +
                                 " joint(s); give a label table or a skeleton.json");
      auto relabelled = vtkSmartPointer<vtkImageData>::New();
      relabelled->ShallowCopy(rig->GetOutput());
      labels = relabelled;
      skeletonJson = rig->GetSkeletonJSON();
      skeletonName = "automatic skeleton";
      if (rig->GetOutputLabelTableTSV() && *rig->GetOutputLabelTableTSV())
        result_.table = parseLabelTable(rig->GetOutputLabelTableTSV(), "automatic skeleton's label table");
    } else {
      if (request_.skeletonPath.isEmpty())
        throw std::runtime_error("choose a skeleton.json or the automatic skeleton");
      skeletonName = request_.skeletonPath.toStdString();
      skeletonJson = readTextFile(skeletonName);
    }
    pipeline->prepare(labels, labelsPath, skeletonJson, skeletonName, image, request_.imagePath.toStdString(),
                      request_.settings);
    if (image) {
      pipeline->setRestImage(image, request_.imagePath.toStdString());
      result_.image = image;
    }
    result_.title = QFileInfo(request_.labelsPath).fileName();
  }
  if (save) {
    stage("saving the prepared case");
    pipeline->saveCase(request_.saveCaseDir.toStdString(), labelsExt);
  }
  if (cancelled_) throw Cancelled();
  pipeline->setProgress(nullptr);
  pipeline->setCancelCheck(nullptr);
  QStringList report;
  for (const auto& line : pipeline->reportLines()) report << QString::fromStdString(line);
  result_.report = report.join('\n');
  result_.pipeline = pipeline;
}

}  // namespace repose
