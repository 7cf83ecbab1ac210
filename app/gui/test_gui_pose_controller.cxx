// Pose state of the GUI: angle conventions, limits, drag rotations, undo/redo. No display.
#include <QSignalSpy>
#include <QtTest>

#include "pose_controller.h"

using namespace repose;

namespace {
Skeleton threeJoints() {
  return parseSkeletonJson(R"({"joints": [
    {"name": "pelvis", "parent": null, "center": [0, 0, 0], "labels": [1]},
    {"name": "left_hip", "parent": "pelvis", "center": [50, 0, -20], "labels": [2]},
    {"name": "left_knee", "parent": "left_hip", "center": [50, 0, -420], "labels": [3]}]})");
}
double angleBetween(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return Eigen::AngleAxisd(a.transpose() * b).angle();
}
}  // namespace

class TestPoseController : public QObject {
  Q_OBJECT
private slots:
  void anglesAreAnatomical() {
    PoseController c;
    c.setSkeleton(threeJoints());
    const int hip = 1, knee = 2;
    // Hip flexion is positive and swings the thigh forwards (LPS: anterior is -y).
    c.setAngles(hip, {60, 0, 0});
    QVERIFY(std::fabs(c.angles(hip).x() - 60) < 1e-9);
    const Eigen::Vector3d kneeCentre = c.globalTransforms()[hip] * c.skeleton().joints[knee].center;
    QVERIFY(kneeCentre.y() < -300);
    // Knee flexion is positive too and swings the shin backwards relative to the thigh.
    c.resetAll();
    c.setAngles(knee, {45, 0, 0});
    const Eigen::Vector3d below = c.skeleton().joints[knee].center + Eigen::Vector3d(0, 0, -100);
    QVERIFY((c.globalTransforms()[knee] * below).y() > 60);
    // Abduction of the left hip moves the knee to the patient's left (+x).
    c.resetAll();
    c.setAngles(hip, {0, 30, 0});
    QVERIFY((c.globalTransforms()[hip] * c.skeleton().joints[knee].center).x() > 200);
    QCOMPARE(c.jointClass(hip).kind, JointKind::Hip);
  }

  void limitsClamp() {
    PoseController c;
    c.setSkeleton(threeJoints());
    const int knee = c.skeleton().find("left_knee");
    const JointLimits l = c.limits(knee);
    QVERIFY(l.upper.x() > 90 && l.upper.y() < 45);  // a hinge: wide flexion, little abduction
    c.setAngles(knee, {400, 400, 0});
    QVERIFY(std::fabs(c.angles(knee).x() - l.upper.x()) < 1e-9);
    QVERIFY(std::fabs(c.angles(knee).y() - l.upper.y()) < 1e-9);
    QVERIFY_EXCEPTION_THROWN(c.setAngles(7, {0, 0, 0}), std::invalid_argument);
  }

  void skeletonChangeComesFirst() {
    // Views keep joint indices; they must hear of a new skeleton before its first pose.
    PoseController c;
    c.setSkeleton(threeJoints());
    QStringList order;
    connect(&c, &PoseController::skeletonChanged, [&] { order << "skeleton"; });
    connect(&c, &PoseController::poseChanged, [&] {
      order << "pose";
      for (int j = 0; j < c.jointCount(); ++j) c.angles(j);  // what a joint view does
    });
    c.setSkeleton(Skeleton());
    QCOMPARE(order, QStringList({"skeleton", "pose"}));
    QCOMPARE(c.jointCount(), 0);
    c.setSkeleton(threeJoints());
    QCOMPARE(c.jointCount(), 3);
  }

  void unsavedAndHandPoses() {
    PoseController c;
    c.setSkeleton(threeJoints());
    QVERIFY(!c.hasUnsavedPose() && !c.isHandPose());
    c.setAngles(1, {30, 0, 0});
    QVERIFY(c.hasUnsavedPose() && c.isHandPose());
    c.markSaved();
    QVERIFY(!c.hasUnsavedPose() && c.isHandPose());
    // A clip frame is neither unsaved work nor a hand pose.
    Pose frame;
    frame.rotations["left_knee"] = rotationFromEulerAngles({20, 0, 0});
    c.setPose(frame, false);
    QVERIFY(!c.hasUnsavedPose() && !c.isHandPose());
    c.undo();  // back to the hand pose
    QVERIFY(c.isHandPose());
    c.resetAll();
    QVERIFY(!c.isHandPose() && c.hasUnsavedPose());
  }

  void undoRedo() {
    PoseController c;
    c.setSkeleton(threeJoints());
    QSignalSpy changed(&c, &PoseController::poseChanged);
    QVERIFY(!c.canUndo());
    c.setAngles(1, {30, 0, 0});
    c.setAngles(2, {0, 0, 20});
    QCOMPARE(changed.count(), 2);
    QVERIFY(c.canUndo() && !c.canRedo());
    c.undo();
    QVERIFY(c.angles(2).isZero(1e-9));
    QVERIFY(std::fabs(c.angles(1).x() - 30) < 1e-9);
    c.undo();
    QVERIFY(c.pose().rotations.empty());
    QVERIFY(!c.canUndo() && c.canRedo());
    c.redo();
    QVERIFY(std::fabs(c.angles(1).x() - 30) < 1e-9);
    // A new edit drops the redo branch.
    c.setAngles(1, {10, 0, 0});
    QVERIFY(!c.canRedo());
    // Setting the same value again is not a step.
    c.setAngles(1, {10, 0, 0});
    c.undo();
    QVERIFY(std::fabs(c.angles(1).x() - 30) < 1e-9);
  }

  void dragIsOneStep() {
    PoseController c;
    c.setSkeleton(threeJoints());
    c.beginEdit();
    for (int i = 1; i <= 20; ++i) c.setAngles(1, {double(i), 0, 0});
    QVERIFY(!c.canUndo());  // nothing recorded until the drag ends
    c.endEdit();
    QVERIFY(c.canUndo());
    c.undo();
    QVERIFY(c.pose().rotations.empty());
    QVERIFY(!c.canUndo());
    // An edit that changes nothing records nothing.
    c.beginEdit();
    c.endEdit();
    QVERIFY(!c.canUndo());
  }

  void rotateInWorldFollowsTheMouse() {
    PoseController c;
    c.setSkeleton(threeJoints());
    c.setAngles(1, {40, 10, 0});  // the parent of the knee is rotated
    const int knee = 2;
    const Eigen::Matrix3d before = c.globalTransforms()[knee].rotation();
    const Eigen::Quaterniond delta(Eigen::AngleAxisd(0.1, Eigen::Vector3d(0.2, 0.9, 0.1).normalized()));
    c.rotateInWorld(knee, delta);
    const Eigen::Matrix3d after = c.globalTransforms()[knee].rotation();
    // The bone's posed orientation turned by exactly the drag's world rotation.
    QVERIFY2(angleBetween(after, delta.toRotationMatrix() * before) < 1e-9, qPrintable(QString::number(angleBetween(after, delta.toRotationMatrix() * before)) + " angles " + QString::number(c.angles(knee).x()) + "," + QString::number(c.angles(knee).y()) + "," + QString::number(c.angles(knee).z())));
    // The knee's centre stays where its parent puts it.
    const Eigen::Vector3d centre = c.globalTransforms()[knee] * c.skeleton().joints[knee].center;
    const Eigen::Vector3d parentMoves = c.globalTransforms()[1] * c.skeleton().joints[knee].center;
    QVERIFY((centre - parentMoves).norm() < 1e-9);
  }

  void poseRoundTripAndReset() {
    PoseController c;
    c.setSkeleton(threeJoints());
    Pose p;
    p.rotations["left_knee"] = rotationFromEulerAngles({-60, 0, 0});
    p.translation = Eigen::Vector3d(5, 0, 0);
    c.setPose(p);
    QCOMPARE(int(c.pose().rotations.size()), 1);
    QVERIFY(c.pose().rotations.at("left_knee").isApprox(p.rotations.at("left_knee")));
    QVERIFY(c.pose().translation.isApprox(p.translation));
    Pose bad;
    bad.rotations["no_such_joint"] = Eigen::Quaterniond::Identity();
    QVERIFY_EXCEPTION_THROWN(c.setPose(bad), std::invalid_argument);
    QCOMPARE(int(c.pose().rotations.size()), 1);  // unchanged
    c.resetJoint(2);
    QVERIFY(c.pose().rotations.empty());
    c.setAngles(1, {20, 0, 0});
    c.resetAll();
    QVERIFY(c.pose().rotations.empty() && c.pose().translation.isZero());
    // Animation frames do not fill the history.
    PoseController d;
    d.setSkeleton(threeJoints());
    d.setPose(p, false);
    QVERIFY(!d.canUndo());
    QVERIFY(!d.pose().rotations.empty());
  }
};

QTEST_GUILESS_MAIN(TestPoseController)
#include "test_gui_pose_controller.moc"
