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
#include "scan_preparation.h"
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
    steps_ = 5 + (request_.autoSkeleton ? 1 : 0) + (request_.imagePath.isEmpty() ? 0 : 1) + (save ? 1 : 0);
    stage("reading " + QFileInfo(request_.labelsPath).fileName());
    // As `repose prepare` reads it: the same table choice, rig and grid checks.
    ScanSource source;
    source.labelsPath = labelsPath;
    source.labelTablePath = request_.labelTablePath.toStdString();
    source.labelTableOption = "\"Label table .tsv\"";  // the Open a scan dialog's field
    source.imagePath = request_.imagePath.toStdString();
    if (!request_.autoSkeleton) {
      if (request_.skeletonPath.isEmpty()) throw std::runtime_error("choose a skeleton.json or the automatic skeleton");
      source.skeletonPath = request_.skeletonPath.toStdString();
    }
    const ScanForPreparation scan =
        readScanForPreparation(source, [&](const std::string& text) { stage(QString::fromStdString(text)); });
    if (!scan.tableTsv.empty()) result_.table = parseLabelTable(scan.tableTsv, labelsPath + " label table");
    pipeline->prepare(scan.labels, labelsPath, scan.skeletonJson, scan.skeletonName, scan.image, source.imagePath,
                      request_.settings);
    if (scan.image) {
      pipeline->setRestImage(scan.image, source.imagePath);
      result_.image = scan.image;
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
