#include "preprocess_worker.h"

#include <QDir>
#include <QFile>
#include <QFileInfo>
#include <QJsonDocument>
#include <QJsonObject>
#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkPointData.h>

#include "atomic_outputs.h"
#include "phantom.h"
#include "vtkReposeAutoRig.h"
#include "vtkReposePhantomSource.h"

namespace repose {

LabelTable phantomLabelTable() {
  LabelTable table;
  for (const auto& [value, name] : describePhantom(PhantomSize::Tiny).labelNames)
    table.labels.push_back({value, name, inferLabelKind(name)});
  return table;
}

LabelTable findCaseLabelTable(const std::string& caseDir, const Skeleton& skeleton) {
  const QDir dir(QString::fromStdString(caseDir));
  QStringList candidates;
  QFile manifest(dir.filePath("manifest.json"));
  if (manifest.open(QIODevice::ReadOnly)) {
    const QString listed = QJsonDocument::fromJson(manifest.readAll()).object().value("labelTable").toString();
    if (!listed.isEmpty()) candidates << dir.filePath(listed);
  }
  candidates << dir.filePath("labels.tsv") << dir.filePath("../labels.tsv");
  for (const QString& candidate : candidates)
    if (QFileInfo::exists(candidate)) {
      try {
        return readLabelTableFile(candidate.toStdString());
      } catch (const std::exception&) {
        // A broken optional table only costs the names.
      }
    }
  // A case of the built-in phantom made before cases kept their table: every joint is the phantom's.
  const Skeleton phantom = describePhantom(PhantomSize::Tiny).skeleton;
  bool isPhantom = !skeleton.joints.empty();
  for (const Joint& j : skeleton.joints) {
    const int p = phantom.find(j.name);
    isPhantom = isPhantom && p >= 0 && phantom.joints[std::size_t(p)].labels == j.labels;
  }
  return isPhantom ? phantomLabelTable() : LabelTable();
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
    result_.table = findCaseLabelTable(dir, parseSkeletonJson(pipeline->skeletonJson()));
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
    const std::string dir = request_.saveCaseDir.toStdString();
    // The case keeps its label names as labels.tsv (findCaseLabelTable reads them back).
    if (!result_.table.labels.empty()) pipeline->setLabelTableTsv(labelTableToTsv(result_.table));
    pipeline->saveCase(dir, labelsExt);
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
