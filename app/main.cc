// The `wobble` command: parses the command line and hands over to a subcommand. All the work
// is in libwobble; this file only maps failures to messages and exit codes, one table for
// every subcommand (wobble/core/errors.h): 0 ok, 2 bad input of any kind (a file, a flag, a
// script line, a limit), 3 a numerical stop, 130 Ctrl-C, 1 anything else.
#include <CLI/CLI.hpp>
#include <malloc.h>

#include <csignal>
#include <iostream>
#include <memory>
#include <streambuf>
#include <stdexcept>

#include "cli_common.h"
#include "condition.h"
#include "fit.h"
#include "inspect.h"
#ifdef WOBBLE_HAVE_PIPELINES
#include "mesh.h"
#include "render.h"
#include "view.h"
#endif
#include "run.h"
#include "simulate.h"
#include "sweep.h"
#include "wobble/core/distribute.h"
#include "wobble/core/interrupt.h"
#include "wobble/formats/atomic_file.h"
#include "wobble/formats/object_file.h"
#ifdef WOBBLE_HAVE_MPI
#include "wobble/mpi/mpi_distributor.h"
#endif

namespace {
// Ctrl-C asks the work to stop at its next step or frame (wobble/core/interrupt.h); the
// handler is one-shot (SA_RESETHAND), so a second Ctrl-C kills a process that did not stop.
void OnInterrupt(int) { wobble::RequestInterrupt(); }
void CatchInterrupt() {
  struct sigaction action {};
  action.sa_handler = OnInterrupt;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESETHAND;
  sigaction(SIGINT, &action, nullptr);
}

// Discards what is written to it: the printout of MPI ranks other than 0.
class NullBuffer : public std::streambuf {
 protected:
  int overflow(int c) override { return c; }
  std::streamsize xsputn(const char*, std::streamsize n) override { return n; }
};

// Under mpirun every rank runs the command (core/distribute.h); rank 0 alone prints and keeps
// files, the others compute their share and stay quiet. Errors are printed by rank 0; every
// rank exits with the same code, since every rank met the same error.
struct MpiSession {
#ifdef WOBBLE_HAVE_MPI
  std::unique_ptr<wobble::mpi::MpiDistributor> mpi;
#endif
  MpiSession(int* argc, char*** argv) {
    static NullBuffer null;  // static: std::cout flushes it at exit, after main returned
#ifdef WOBBLE_HAVE_MPI
    if (wobble::mpi::LaunchedByMpirun()) mpi = std::make_unique<wobble::mpi::MpiDistributor>(argc, argv);
#else
    (void)argc, (void)argv;
#endif
    if (!wobble::IsOutputRank()) {
      std::cout.rdbuf(&null);
      std::cerr.rdbuf(&null);
      wobble::formats::DiscardOutputs();
    }
  }
};
}  // namespace

// Renders allocate and free a few megabytes per frame (colour and depth read back, the EXR's
// channels and line buffers, the alpha and motion rasters). glibc maps blocks that large
// afresh and gives freed memory back to the kernel, so every frame faulted its pages in
// again: a third of a 300-frame render's CPU went to page faults. Keeping blocks up to 32 MB
// in the heap and never trimming below 1 GB lets each frame reuse the last one's pages
// (README, Pictures: 11.3-12.9 s wall before, about 5.3-5.8 s after, same run).
void ReuseFreedMemory() {
  mallopt(M_MMAP_THRESHOLD, 32 << 20);  // glibc's largest
  mallopt(M_TRIM_THRESHOLD, 1 << 30);
}

int main(int argc, char** argv) {
  using namespace wobble::app;
  ReuseFreedMemory();
  MpiSession mpi(&argc, &argv);
  CatchInterrupt();
  CLI::App app("wobble: dynamic free-form deformation characters (Faloutsos 1995)", "wobble");
  app.set_version_flag("--version", "wobble 0.1");
  app.require_subcommand(1);
  app.failure_message([](const CLI::App*, const CLI::Error& e) {
    return "wobble: " + std::string(e.what()) + "\nRun with --help for more information.\n";
  });
  SimulateArgs simulate_args;
  InspectArgs inspect_args;
  CLI::App* simulate = AddSimulateCommand(&app, &simulate_args);
  CLI::App* inspect = AddInspectCommand(&app, &inspect_args);
  ConditionSweepArgs sweep_args;
  ConditionCheckArgs check_args;
  ConditionTimeArgs time_args;
  const ConditionCommands condition = AddConditionCommand(&app, &sweep_args, &check_args, &time_args);
#ifdef WOBBLE_HAVE_PIPELINES
  const std::string render_what = "frames,filmstrip,charts", export_what = "vtp,exr,disp";
  RenderArgs render_args, export_args;
  CLI::App* render = AddRenderCommand(&app, "render", "Simulate and draw: PNG frames, a filmstrip, energy and cond(M) charts",
                                      render_what, &render_args);
  CLI::App* exporter = AddRenderCommand(&app, "export", "Simulate and export: .vtp/.pvd for ParaView, EXR frames and "
                                        "displacement images", export_what, &export_args);
  ViewArgs view_args;
  CLI::App* view = AddViewCommand(&app, &view_args);
  MeshArgs mesh_args;
  CLI::App* mesh = AddMeshCommand(&app, &mesh_args);
#endif
  FitPoseArgs fit_pose_args;
  FitTrajectoryArgs fit_trajectory_args;
  const FitCommands fit = AddFitCommand(&app, &fit_pose_args, &fit_trajectory_args);
  FitSpacetimeArgs fit_spacetime_args;
  CLI::App* fit_spacetime = AddFitSpacetimeCommand(fit.fit, &fit_spacetime_args);
  RunArgs run_args;
  CLI::App* run = AddRunCommand(&app, &run_args);
  SweepArgs sweep_study_args;
  CLI::App* sweep_study = AddSweepCommand(&app, &sweep_study_args);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version are "errors" with exit code 0; anything else is bad usage
    const int code = app.exit(e);
    return code == 0 ? kExitOk : kExitBadInput;
  }

  try {
    if (simulate->parsed()) return RunSimulate(simulate_args);
    if (inspect->parsed()) return RunInspect(inspect_args);
    if (condition.sweep->parsed()) return RunConditionSweep(sweep_args);
    if (condition.check->parsed()) return RunConditionCheck(check_args);
    if (condition.time->parsed()) return RunConditionTime(time_args);
#ifdef WOBBLE_HAVE_PIPELINES
    if (render->parsed()) return RunRender(render_args, render_what);
    if (exporter->parsed()) return RunRender(export_args, export_what);
    if (view->parsed()) return RunView(view_args);
    if (mesh->parsed()) return RunMesh(mesh_args);
#endif
    if (fit.pose->parsed()) return RunFitPose(fit_pose_args);
    if (fit.trajectory->parsed()) return RunFitTrajectory(fit_trajectory_args);
    if (fit_spacetime->parsed()) return RunFitSpacetime(fit_spacetime_args);
    if (run->parsed()) return RunScript(run_args);
    if (sweep_study->parsed()) return RunSweep(sweep_study_args);
  } catch (const wobble::formats::ParseError& e) {
    std::cerr << e.what() << std::endl;  // already "FILE:LINE: message"
    return kExitBadInput;
  } catch (const wobble::NumericalStop& e) {
    std::cerr << "wobble: " << e.what() << std::endl;  // the cause, and where
    return kExitSimStopped;
  } catch (const wobble::Interrupted& e) {
    std::cerr << "\nwobble: " << e.what() << std::endl;
    return kExitInterrupted;
  } catch (const std::invalid_argument& e) {
    // UsageError, InputError, LimitExceeded: a value out of range, modes that do not fit, ...
    std::cerr << "wobble: " << e.what() << std::endl;
    return kExitBadInput;
  } catch (const std::exception& e) {
    std::cerr << "wobble: " << e.what() << std::endl;
    return kExitFailure;
  }
  return kExitFailure;
}
