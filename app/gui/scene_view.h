#pragma once
// The 3D view: skin translucent, bones and other tissues opaque in their label colours, the
// skeleton (joints and bones) drawn on top, and the selected joint's rotation rings. Clicking a
// bone selects its joint; dragging from a bone rotates that joint like a trackball (onDragRotate).
#include <functional>
#include <vector>

#include <Eigen/Geometry>
#include <QVTKOpenGLNativeWidget.h>
#include <vtkSmartPointer.h>

#include "label_table.h"
#include "skeleton.h"

class vtkActor;
class vtkLookupTable;
class vtkPolyData;
class vtkRenderer;

namespace repose {

class SceneView : public QVTKOpenGLNativeWidget {
  Q_OBJECT
public:
  explicit SceneView(QWidget* parent = nullptr);
  ~SceneView() override;

  /// Splits the rest surfaces (cell data "Label", -1 = skin) into skin and tissue actors sharing
  /// the posed points, and builds the skeleton overlay. Resets the camera. `table` names the labels.
  void setCase(vtkPolyData* restSurfaces, const Skeleton& skeleton, const LabelTable& table);
  void clearCase();
  /// New posed points (same vertices as the rest surfaces) and joint transforms. Does not render.
  void updatePose(vtkPolyData* posedSurfaces, const std::vector<Eigen::Isometry3d>& global);
  /// Ghost of another posed state (the FEM "before"); null hides it.
  void setGhost(vtkPolyData* surfaces);
  void render();

  void setSelectedJoint(int joint);
  int selectedJoint() const { return selected_; }
  /// World rotation a mouse drag of (dx, dy) pixels applies (the drag and the benchmark use it).
  Eigen::Quaterniond dragRotation(double dx, double dy) const;
  /// Joint of the bone under display position (x, y) (VTK pixels, origin bottom left), or -1.
  /// Names the picked structure in the view's caption.
  int pickJoint(int x, int y);
  /// The joint whose bone or surface label is `label`, or -1.
  int jointOfLabel(int label) const;

  /// While interacting (a drag, playback) large surfaces are drawn decimated: the coarse mesh's
  /// vertices are a subset of the full ones, so posing it is a gather. Off draws full detail.
  void setInteractive(bool interactive);
  bool interactive() const { return interactive_; }
  /// Triangles drawn while interacting (0: no coarse level, the surfaces are small enough).
  vtkIdType interactiveTriangles() const;
  /// Surfaces above this many triangles get the coarse level (default 120 000); applies from the
  /// next setCase().
  void setLodThreshold(vtkIdType triangles) { lodThreshold_ = triangles; }
  /// The coarse skin (0) or tissue (1) surface drawn while interacting, or null.
  vtkPolyData* interactiveSurface(int which) const;

  /// Keep the camera on the body: the view moves by the root joint's displacement between poses.
  void setCameraFollow(bool follow) { follow_ = follow; }
  bool cameraFollows() const { return follow_; }
  /// The caption naming the picked structure ("femur_left (label 75), joint left_hip").
  QString pickedCaption() const;

  void setSkinOpacity(double opacity);
  void setSkeletonVisible(bool visible);
  void resetCamera();
  /// Writes the current view as PNG; throws std::runtime_error on failure.
  void saveScreenshot(const std::string& path);

  vtkActor* skinActor() const;
  vtkActor* tissueActor() const;
  vtkRenderer* renderer() const;

  /// Called for every mouse move of a drag started on a bone.
  std::function<void(int joint, const Eigen::Quaterniond& worldDelta)> onDragRotate;

signals:
  void jointPicked(int joint);
  void dragStarted(int joint);
  void dragEnded();

private:
  void updateSkeletonGeometry();
  void buildLod(vtkPolyData* rest, vtkLookupTable* lut, int maxLabel);
  void updateLodPoints();
  void dropLod();
  struct Impl;
  Impl* d_;
  int selected_ = -1;
  bool interactive_ = false;
  bool follow_ = true;
  vtkIdType lodThreshold_ = 120000;
  friend class SceneInteractorStyle;
};

}  // namespace repose
