// The `repose` command line: the command named by argv[1] runs; its errors end here as one line.
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <string>

#include <vtkLogger.h>
#include <vtkNew.h>
#include <vtkOutputWindow.h>

#include "animate_command.h"
#include "atomic_outputs.h"
#include "batch_command.h"
#include "cli_options.h"
#include "demo_command.h"
#include "interrupt_cleanup.h"
#include "phantom_command.h"
#include "pose_command.h"
#include "prepare_command.h"
#include "repose_version.h"
#include "rig_command.h"
#include "voxelize_command.h"

namespace {

const char* kMainUsage =
    "usage: repose COMMAND [OPTIONS]\n"
    "Repose a segmented CT/MRI scan: tet mesh, harmonic bone weights, skinning, posed volume.\n\n"
    "commands:\n"
    "  demo      built-in phantom -> prepare -> pose; writes every output and render.png\n"
    "  phantom   write the built-in phantom's labels.nii.gz and skeleton.json\n"
    "  prepare   mesh a label volume, compute bone weights and bind surfaces (once per scan)\n"
    "  pose      pose a prepared case: posed label volume, mesh and surfaces\n"
    "  animate   drive a prepared case with a BVH motion clip: a ParaView time series\n"
    "  rig       find the joints from the bone labels and write an editable skeleton.json\n"
    "  voxelize  surface meshes (skin, bones, tissues) -> a label volume and its label table\n"
    "  batch     many subjects x poses and BVH frames from a manifest, on Dask (a local or a remote cluster)\n\n"
    "Run 'repose COMMAND --help' for the options of a command; 'repose --version' prints the version.\n";

/// VTK's warnings and errors go to stderr as single lines; failures are reported by the caller.
class QuietOutputWindow : public vtkOutputWindow {
public:
  static QuietOutputWindow* New() { return new QuietOutputWindow; }
  void DisplayText(const char* text) override { show(text); }
  void DisplayErrorText(const char* text) override { show(text); }
  void DisplayWarningText(const char* text) override { show(text); }
  void DisplayGenericWarningText(const char* text) override { show(text); }
  void DisplayDebugText(const char* text) override { show(text); }

private:
  static void show(const char* text) {
    if (std::getenv("REPOSE_VERBOSE")) std::cerr << text;
  }
};

/// Runs the command argv[1]; returns its exit code.
int runCommand(const std::string& command, int argc, char** argv) {
  if (command == "demo") return repose::runDemoCommand(argc, argv, 2);
  if (command == "phantom") return repose::runPhantomCommand(argc, argv, 2);
  if (command == "prepare") return repose::runPrepareCommand(argc, argv, 2);
  if (command == "pose") return repose::runPoseCommand(argc, argv, 2);
  if (command == "voxelize") return repose::runVoxelizeCommand(argc, argv, 2);
  if (command == "batch") repose::execBatchRunner(argc, argv, 2);  // the Python runner; returns only by throwing
  if (command == "rig") return repose::runRigCommand(argc, argv, 2);
  if (command == "animate") return repose::runAnimateCommand(argc, argv, 2);
  throw repose::UsageError("unknown command '" + command + "' (see repose --help)");
}

}  // namespace

int main(int argc, char** argv) {
  repose::cleanUpOnInterrupt();
  std::signal(SIGXFSZ, SIG_IGN);  // past `ulimit -f` a write fails (EFBIG) and is reported, no core dump
  vtkNew<QuietOutputWindow> quiet;
  vtkOutputWindow::SetInstance(quiet);
  if (!std::getenv("REPOSE_VERBOSE")) vtkLogger::SetStderrVerbosity(vtkLogger::VERBOSITY_OFF);
  if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h") || !std::strcmp(argv[1], "help")) {
    std::cout << kMainUsage;
    return argc < 2 ? 2 : 0;
  }
  const std::string command = argv[1];
  if (command == "--version") return std::cout << "repose " << REPOSE_VERSION << "\n", 0;
  try {
    return runCommand(command, argc, argv);
  } catch (const repose::UsageError& e) {
    std::cerr << "repose: error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::string msg = repose::withFinalPaths(e.what());
    for (char& c : msg)
      if (c == '\n') c = ' ';
    std::cerr << "repose: error: " << msg << "\n";
    return 1;
  }
}
