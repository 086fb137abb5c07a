// The interactive viewer (pipelines/interactive_view.h) driven without a person: events are
// played into its interactor with vtkInteractorEventRecorder (the format `wobble view
// --play-events` reads) or invoked one by one, and every frame advances a fixed 1/fps of
// simulated time, so runs are reproducible.
//
//   - a recorded drag picks a point, and the world then moves exactly like a World stepped
//     on its own with a spring from that point to the cursor (same steps, 1e-12), and the
//     point comes closer to the cursor;
//   - a click on a mode's slider sets that mode's PD target to the value under the cursor and
//     the amplitude follows it;
//   - the key `l` hides the lattice (and the pixels of its colour go away);
//   - the session script, run by the interpreter, ends in the viewer's state (1e-9), also
//     with a pose graph from a script driving the targets and a slider taking over;
//   - screenshots of the window against baselines (render_baseline.h);
//   - a Witkin & Welch scene (data/fig2_triple_pendulum.wob): the viewer steps the script's
//     scene exactly as `simul` does (same state, 1e-12) with the nail holding; a drag picks the
//     named point under the cursor and its trajectory constraint takes it to the cursor, and
//     releasing removes the constraint; the key `a` hides the anchors (their pixels go away).
// Without DISPLAY every test skips (VTK 9.1 needs X).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vtkCommand.h>
#include <vtkImageData.h>
#include <vtkInteractorEventRecorder.h>
#include <vtkRenderWindow.h>
#include <vtkRenderWindowInteractor.h>
#include <vtkSliderRepresentation2D.h>
#include <vtkSliderWidget.h>

#include <fstream>
#include <sstream>

#include "pipelines/interactive_view.h"
#include "support/pipelines_test_util.h"
#include "support/render_baseline.h"
#include "wobble/script/interpreter.h"
#include "support/source_paths.h"

namespace wobble::pipelines {
namespace {

using testing::Table;
using testing::Vec;
using testing_render::CompareWithBaseline;

const std::string kData = wobble::test_env::DataDir();

// The table of data/ in a scene, as `wobble view data/table.obj --modes data/table_modes.def`
// loads it: the thesis integrator, dt 0.01, at rest at q0.
std::unique_ptr<scene::Scene> TableScene(const Eigen::VectorXd& q0) {
  auto s = std::make_unique<scene::Scene>();
  s->object().Load(kData + "/table.obj");
  s->object().LoadModes({kData + "/table_modes.def"});
  s->options().integrator = Integrator::kThesis;
  s->options().dt = 0.01;
  s->object().SetState(q0, Eigen::VectorXd::Zero(q0.size()));
  return s;
}

ViewerOptions TestOptions() {
  ViewerOptions o;
  o.width = 800;
  o.height = 500;
  o.fixed_frame_time = true;  // every frame advances 1/30 s: reproducible
  o.chart_every = 5;
  return o;
}

// Plays events written in vtkInteractorEventRecorder's format into the view's interactor.
template <class View> void Play(View* view, const std::string& events) {
  auto recorder = vtkSmartPointer<vtkInteractorEventRecorder>::New();
  recorder->SetInteractor(view->interactor());
  recorder->ReadFromInputStringOn();
  recorder->SetInputString(events.c_str());
  recorder->Play();
  recorder->Off();
}

std::string Event(const char* name, double x, double y, char key = 0, const char* sym = "0") {
  std::ostringstream s;
  s << name << " " << std::lround(x) << " " << std::lround(y) << " 0 0 " << int(key) << " 0 " << sym << "\n";
  return s.str();
}

template <class View> void PressKey(View* view, char key) {
  vtkRenderWindowInteractor* i = view->interactor();
  i->SetKeyEventInformation(0, 0, key, 1, std::string(1, key).c_str());
  i->InvokeEvent(vtkCommand::KeyPressEvent);
  i->InvokeEvent(vtkCommand::CharEvent);
  i->InvokeEvent(vtkCommand::KeyReleaseEvent);
}

// Pixels of the scene's part of the window (left of the charts, above the sliders) within 20
// (of 255) of a colour.
long CountColour(vtkImageData* image, double r, double g, double b) {
  int dims[3];
  image->GetDimensions(dims);
  long n = 0;
  for (int y = int(0.22 * dims[1]) + 1; y < dims[1]; ++y)
    for (int x = 0; x < int(0.62 * dims[0]); ++x) {
      const auto* p = static_cast<const unsigned char*>(image->GetScalarPointer(x, y, 0));
      if (std::abs(p[0] - r * 255) < 20 && std::abs(p[1] - g * 255) < 20 && std::abs(p[2] - b * 255) < 20) ++n;
    }
  return n;
}

// Display position of a slider's value (its tube runs between Point1 and Point2).
Eigen::Vector2d SliderPixel(InteractiveView* view, vtkSliderWidget* w, double value) {
  auto* rep = vtkSliderRepresentation2D::SafeDownCast(w->GetRepresentation());
  int* size = view->window()->GetSize();
  const double* p1 = rep->GetPoint1Coordinate()->GetValue();
  const double* p2 = rep->GetPoint2Coordinate()->GetValue();
  const double f = (value - rep->GetMinimumValue()) / (rep->GetMaximumValue() - rep->GetMinimumValue());
  return {(p1[0] + f * (p2[0] - p1[0])) * size[0], (p1[1] + f * (p2[1] - p1[1])) * size[1]};
}

TEST(InteractiveView, RecordedDragPullsThePointLikeASpringToTheCursor) {
  REQUIRE_DISPLAY();
  // the table standing on its feet
  auto table = TableScene(Vec({0, 0, 0, 0, 0, 0, 0}));
  InteractiveView view(*table, TestOptions());
  view.Initialize();  // opens the window and draws once; no event loop
  for (int k = 0; k < 10; ++k) view.Frame();  // let it settle a little
  // press on the top right corner of the table top, pull up and to the right
  const Eigen::Vector2d corner = WorldPositionOf(view.world(), 0, Eigen::Vector2d(1.0, 1.0));
  const Eigen::Vector2d press = view.WorldToDisplay(corner).head<2>();
  const Eigen::Vector2d cursor_px = press + Eigen::Vector2d(40, 60);
  std::string events = Event("MouseMoveEvent", press.x(), press.y()) + Event("LeftButtonPressEvent", press.x(), press.y()) +
                       Event("MouseMoveEvent", cursor_px.x(), cursor_px.y());
  Play(&view, events);
  ASSERT_TRUE(view.dragged_point().has_value()) << "the press did not pick a point";
  const Eigen::Vector2d st = view.dragged_point()->u;
  const Eigen::Vector2d cursor = view.DisplayToWorld(std::lround(cursor_px.x()), std::lround(cursor_px.y()));
  const double before = (WorldPositionOf(view.world(), 0, st) - cursor).norm();

  // (on the ground the contacts' anchors are state too; the exact comparison with an
  // independent World is the next test, in the air)
  std::string frames;
  for (int k = 0; k < 30; ++k) frames += Event("TimerEvent", cursor_px.x(), cursor_px.y());
  Play(&view, frames);
  const double after = (WorldPositionOf(view.world(), 0, st) - cursor).norm();
  EXPECT_LT(after, 0.6 * before) << "the pulled point did not come toward the cursor: " << before << " -> " << after;
  // the spring is drawn while pulling (the springs layer) and goes away on release
  EXPECT_EQ(view.world().options().params.springs.size(), 1u);
  Play(&view, Event("LeftButtonReleaseEvent", cursor_px.x(), cursor_px.y()));
  EXPECT_FALSE(view.dragged_point().has_value());
  EXPECT_TRUE(view.world().options().params.springs.empty());
}

TEST(InteractiveView, DragInTheAirMatchesAWorldWithASpring) {
  REQUIRE_DISPLAY();
  // no ground: the state is q and q̇ alone, so an independent World can follow exactly
  auto table = TableScene(Vec({0, 200, 0.1, 0, 0, 0, 0}));
  table->options().params.ground.enabled = false;
  const scene::SimulationSetup start = table->CurrentSetup();
  InteractiveView view(*table, TestOptions());
  view.Initialize();
  const Eigen::Vector2d point = WorldPositionOf(view.world(), 0, Eigen::Vector2d(0.0, 1.0));
  const Eigen::Vector2d press = view.WorldToDisplay(point).head<2>();
  const Eigen::Vector2d cursor_px = press + Eigen::Vector2d(-50, 30);
  Play(&view, Event("LeftButtonPressEvent", press.x(), press.y()) + Event("MouseMoveEvent", cursor_px.x(), cursor_px.y()));
  ASSERT_TRUE(view.dragged_point().has_value());
  const Eigen::Vector2d st = view.dragged_point()->u;
  const Eigen::Vector2d cursor = view.DisplayToWorld(std::lround(cursor_px.x()), std::lround(cursor_px.y()));

  World ref(start.world);
  ref.AddBody(start.body);
  ref.SetState(0, start.q, start.qd);
  Spring sp = view.world().options().params.springs.at(0);
  EXPECT_EQ(sp.LatticeCoords<2>(), st);
  EXPECT_NEAR((sp.Anchor<2>() - cursor).norm(), 0.0, 1e-9);
  ref.AddSpring(sp);
  const double before = (WorldPositionOf(view.world(), 0, st) - cursor).norm();
  std::string frames;
  for (int k = 0; k < 45; ++k) frames += Event("TimerEvent", cursor_px.x(), cursor_px.y());
  Play(&view, frames);
  for (long n = 0; n < view.session_steps(); ++n) ASSERT_TRUE(ref.Step());
  EXPECT_EQ(ref.steps(), view.world().steps());
  const Eigen::VectorXd dq = view.world().q(0) - ref.q(0);
  EXPECT_LT(dq.cwiseAbs().maxCoeff(), 1e-9) << "viewer " << view.world().q(0).transpose() << "\nreference "
                                           << ref.q(0).transpose();
  const double after = (WorldPositionOf(view.world(), 0, st) - cursor).norm();
  EXPECT_LT(after, before);
  // the match with the independent World (gravity, modes, the spring) is the check that the
  // rest of the body moves by the same passive dynamics
}

TEST(InteractiveView, SliderClickSetsTheModeTargetAndTheAmplitudeFollows) {
  REQUIRE_DISPLAY();
  auto table = TableScene(Vec({0, 0, 0, 0, 0, 0, 0}));
  InteractiveView view(*table, TestOptions());
  view.Initialize();
  const int bend = 0;  // data/table_modes.def: bend is the first mode
  const Eigen::Vector2d at = SliderPixel(&view, view.mode_slider(bend), 0.25);
  Play(&view, Event("MouseMoveEvent", at.x(), at.y()) + Event("LeftButtonPressEvent", at.x(), at.y()) +
                  Event("LeftButtonReleaseEvent", at.x(), at.y()));
  const double target = view.mode_targets()[bend];
  // the target is the slider's value; the slider maps its travel inside the end caps, a few
  // pixels short of Point1..Point2, so the value under the cursor is 0.25 within 0.05
  EXPECT_EQ(target, static_cast<vtkSliderRepresentation*>(view.mode_slider(bend)->GetRepresentation())->GetValue());
  EXPECT_NEAR(target, 0.25, 0.05) << "the click on the slider's tube at 0.25";
  for (int d = 1; d < 4; ++d) EXPECT_EQ(view.mode_targets()[d], 0.0);
  std::string frames;
  for (int k = 0; k < 60; ++k) frames += Event("TimerEvent", 10, 10);
  Play(&view, frames);
  const double gamma = view.world().q(0)[3 + bend];
  EXPECT_GT(gamma, 0.6 * target) << "the bend amplitude did not follow its target";
  EXPECT_LT(gamma, 1.4 * target);
}

TEST(InteractiveView, KeyTogglesTheLatticeAndScreenshotsMatchBaselines) {
  REQUIRE_DISPLAY();
  auto table = TableScene(Vec({0, 60, 0.1, 0.1, 0, 0, 0}));
  InteractiveView view(*table, TestOptions());
  view.Initialize();
  for (int k = 0; k < 15; ++k) view.Frame();
  auto with = view.Capture();
  const double lattice_rgb[3] = {0.45, 0.6, 0.85};
  const long lattice_pixels = CountColour(with, lattice_rgb[0], lattice_rgb[1], lattice_rgb[2]);
  EXPECT_TRUE(view.LayerVisible(SceneLayer::kLattice));
  PressKey(&view, 'l');
  EXPECT_FALSE(view.LayerVisible(SceneLayer::kLattice));
  auto without = view.Capture();
  const long left = CountColour(without, lattice_rgb[0], lattice_rgb[1], lattice_rgb[2]);
  EXPECT_GT(lattice_pixels, 200);
  EXPECT_LT(left, lattice_pixels / 4) << "lattice-coloured pixels remain after 'l'";
  CompareWithBaseline("view_window", with);
  CompareWithBaseline("view_no_lattice", without);
  PressKey(&view, 'l');
  EXPECT_TRUE(view.LayerVisible(SceneLayer::kLattice));
  // space pauses: frames then leave the world alone
  PressKey(&view, ' ');
  EXPECT_FALSE(view.playing());
  const long steps = view.world().steps();
  view.Frame();
  EXPECT_EQ(view.world().steps(), steps);
  // n steps once
  PressKey(&view, 'n');
  EXPECT_EQ(view.world().steps(), steps + 1);
}

TEST(InteractiveView, TimeSliderScrubsRecordedFrames) {
  REQUIRE_DISPLAY();
  auto table = TableScene(Vec({0, 60, 0, 0, 0, 0, 0}));
  InteractiveView view(*table, TestOptions());
  view.Initialize();
  for (int k = 0; k < 20; ++k) view.Frame();
  ASSERT_EQ(view.num_recorded_frames(), 21);  // the start and 20 frames
  const Eigen::Vector2d at = SliderPixel(&view, view.time_slider(), 5.0);
  Play(&view, Event("MouseMoveEvent", at.x(), at.y()) + Event("LeftButtonPressEvent", at.x(), at.y()) +
                  Event("LeftButtonReleaseEvent", at.x(), at.y()));
  EXPECT_FALSE(view.playing());
  EXPECT_NE(view.StatusLine().find("recorded frame 5:"), std::string::npos) << view.StatusLine();
  // the live world is untouched; space goes back to it and plays on
  const long steps = view.world().steps();
  PressKey(&view, ' ');
  EXPECT_TRUE(view.playing());
  view.Frame();
  EXPECT_GT(view.world().steps(), steps);
}

void ExpectReplayMatches(InteractiveView& view, const std::string& name) {
  const std::string dir = testing::TempDir(name);
  const std::string path = dir + "/session.wob";
  view.SaveSession(path);
  std::ostringstream out;
  script::Interpreter interp(out);
  interp.RunFile(path);
  const Eigen::VectorXd& q = interp.q();
  ASSERT_EQ(q.size(), view.world().q(0).size());
  const Eigen::VectorXd d = q - view.world().q(0);
  EXPECT_LT(d.cwiseAbs().maxCoeff(), 1e-9) << "replay " << q.transpose() << "\nviewer " << view.world().q(0).transpose()
                                          << "\nscript:\n" << view.SessionScriptText();
  EXPECT_NEAR(interp.time(), view.time(), 1e-9);
}

TEST(InteractiveView, SavedSessionReplaysToTheSameState) {
  REQUIRE_DISPLAY();
  // dropped onto the ground; targets changed three times while it plays, once in the same
  // frame as a step boundary would be ambiguous without the half-step rule
  auto table = TableScene(Vec({0, 30, 0, 0, 0, 0, 0}));
  InteractiveView view(*table, TestOptions());
  view.Initialize();
  for (int k = 0; k < 20; ++k) view.Frame();
  view.SetModeTarget(0, 0.2);
  for (int k = 0; k < 20; ++k) view.Frame();
  view.SetModeTarget(1, -0.15);
  view.SetModeTarget(2, 0.05);  // a passive mode: the script makes every mode active, codamA 0
  for (int k = 0; k < 25; ++k) view.Frame();
  view.StepOnce();
  view.SetModeTarget(0, -0.1);
  view.SetPlaying(true);
  for (int k = 0; k < 15; ++k) view.Frame();
  ExpectReplayMatches(view, "view_replay");
  EXPECT_EQ(view.SessionScriptText().find("pull"), std::string::npos);
}

TEST(InteractiveView, ScriptPoseGraphDrivesTheTargetsAndReplays) {
  REQUIRE_DISPLAY();
  // a script like data/bounding_table.wob without the anneal: its pose graph drives the
  // active modes until a slider takes over
  const std::string dir = testing::TempDir("view_script");
  const std::string script = dir + "/gait.wob";
  std::ofstream(script) << "load_obj " << kData << "/table.obj\nload_def " << kData << "/table_modes.def\n"
                        << "set codamA 250000\nset integrator thesis\nset dt 0.01\nset grconst 45000\nset grdam 3000\n"
                        << "set frconst 3000\nset frsin 0.5\nset_vec q 0 0 0 0 0 0 0\n"
                        << "pose 0.1 0 0.4\npose 0 -0.1 0.4\npose -0.1 0 0.4\npose 0 0.1 0.4\n"
                        << "spring 0.5 1 150 200 200 10\n";
  std::ostringstream out;
  script::Interpreter interp(out);
  interp.RunFile(script);
  const scene::SimulationSetup setup = interp.scene().CurrentSetup();
  ASSERT_TRUE(setup.body);
  ASSERT_EQ(setup.world.params.springs.size(), 1u);
  InteractiveView view(interp.scene(), TestOptions());
  view.Initialize();
  for (int k = 0; k < 40; ++k) view.Frame();  // 1.33 s: poses 0..3 and 0 again
  EXPECT_NE(view.mode_targets().norm(), 0.0);
  // the sliders show the graph's targets as it drives them (within the sliders' range)
  for (int d = 0; d < view.mode_targets().size(); ++d)
    EXPECT_EQ(static_cast<vtkSliderRepresentation*>(view.mode_slider(d)->GetRepresentation())->GetValue(),
              std::clamp(view.mode_targets()[d], -TestOptions().slider_range, TestOptions().slider_range))
        << "mode " << d;
  view.SetModeTarget(3, 0.05);  // the slider takes over from the graph
  const Eigen::VectorXd held = view.mode_targets();
  for (int k = 0; k < 30; ++k) view.Frame();
  EXPECT_EQ(view.mode_targets(), held) << "the pose graph still drives after a slider moved";
  ExpectReplayMatches(view, "view_script_replay");
}

// A character session is the scene's own run: a script whose pose graph switches smoothly
// (`set switch_width`) plays in the viewer exactly as the interpreter's `simul` runs it.
TEST(InteractiveView, CharacterSessionIsTheScenesRunAsSimulRunsIt) {
  REQUIRE_DISPLAY();
  const std::string dir = testing::TempDir("view_smooth");
  const std::string script = dir + "/smooth.wob";
  std::ofstream(script) << "load_obj " << kData << "/table.obj\nload_def " << kData << "/table_modes.def\n"
                        << "set codamA 250000\nset integrator thesis\nset dt 0.01\nset switch_width 0.1\n"
                        << "set_vec q 0 0 0 0 0 0 0\npose 0.1 0 0.3\npose 0 -0.1 0.3\n";
  std::ostringstream out;
  script::Interpreter interp(out);
  interp.RunFile(script);
  Eigen::VectorXd q;
  {
    InteractiveView view(interp.scene(), TestOptions());
    view.Initialize();
    for (int k = 0; k < 30; ++k) view.Frame();  // 1 s: 100 steps
    EXPECT_EQ(view.session_steps(), 100);
    q = view.world().q(0);
  }
  script::Interpreter ref(out);
  ref.RunFile(script);
  ref.RunLine("simul 1", "<test>", 1, dir);
  EXPECT_LT((ref.q() - q).cwiseAbs().maxCoeff(), 1e-12) << "simul " << ref.q().transpose() << "\nviewer " << q.transpose();
  EXPECT_GT(q.tail(4).cwiseAbs().maxCoeff(), 1e-3);  // the graph moved the modes
  // the view ended its run: the object goes on from where the viewer left it
  EXPECT_LT((interp.q() - q).cwiseAbs().maxCoeff(), 1e-15);
}

// The table at rest at the origin (thesis integrator, dt 0.01) with `keys` (script lines), as
// dir/keys.wob; returns its path.
std::string KeyedTableScript(const std::string& dir, const std::string& keys) {
  const std::string script = dir + "/keys.wob";
  std::ofstream(script) << "load_obj " << kData << "/table.obj\nload_def " << kData << "/table_modes.def\n"
                        << "set integrator thesis\nset dt 0.01\nset_vec q 0 0 0 0 0 0 0\n" << keys;
  return script;
}

// A script stopped at `keyframe` (ViewerOptions::keys_first): the viewer plays the keys, then
// simulates on from where they end, as the interpreter's `keyframe` and `simul` do.
TEST(InteractiveView, KeysPlayFirstThenTheSimulationGoesOn) {
  REQUIRE_DISPLAY();
  const std::string dir = testing::TempDir("view_keys");
  const std::string script = KeyedTableScript(dir, "key 0 bend=0\nkey 0.3 bend=0.2\nkey 0.5 bend=-0.1\n");
  std::ostringstream out;
  script::Interpreter interp(out);
  interp.RunFile(script);
  ViewerOptions options = TestOptions();
  options.keys_first = true;
  Eigen::VectorXd at_keys_end, q;
  {
    InteractiveView view(interp.scene(), options);
    view.Initialize();
    for (int k = 0; k < 15; ++k) view.Frame();  // 0.5 s: the keys
    EXPECT_NEAR(view.world().time(), 0.5, 1e-12);
    at_keys_end = view.world().q(0);
    for (int k = 0; k < 15; ++k) view.Frame();  // 0.5 s more, simulated
    EXPECT_EQ(view.session_steps(), 100);
    q = view.world().q(0);
  }
  script::Interpreter ref(out);
  ref.RunFile(script);
  ref.RunLine("keyframe", "<test>", 1, dir);
  EXPECT_NEAR(ref.q()[3], -0.1, 1e-12) << "the last key's bend";
  EXPECT_LT((ref.q() - at_keys_end).cwiseAbs().maxCoeff(), 1e-12) << "keyframe " << ref.q().transpose()
                                                                   << "\nviewer " << at_keys_end.transpose();
  ref.RunLine("simul 0.5", "<test>", 2, dir);
  EXPECT_LT((ref.q() - q).cwiseAbs().maxCoeff(), 1e-12) << "simul " << ref.q().transpose() << "\nviewer " << q.transpose();
  EXPECT_GT((q - at_keys_end).cwiseAbs().maxCoeff(), 1e-3) << "the body moves on after the keys";
}

// The saved session of a keyframed start plays the same keys (a held foot, smooth
// interpolation) before it simulates with the slider changes made after the hand-over.
TEST(InteractiveView, SavedSessionOfAKeyframedStartReplaysTheKeys) {
  REQUIRE_DISPLAY();
  const std::string script = KeyedTableScript(testing::TempDir("view_keys_save"),
                                              "hold 0.1 0\nset interp smooth\nkey 0 bend=0\n"
                                              "key 0.3 bend=0.2 shear=0.05\nkey 0.5 bend=-0.1\n");
  std::ostringstream out;
  script::Interpreter interp(out);
  interp.RunFile(script);
  ViewerOptions options = TestOptions();
  options.keys_first = true;
  InteractiveView view(interp.scene(), options);
  view.Initialize();
  for (int k = 0; k < 6; ++k) view.Frame();  // inside the keys: the replay plays them all
  EXPECT_NE(view.SessionScriptText().find("saved while the keys played"), std::string::npos) << view.SessionScriptText();
  for (int k = 0; k < 14; ++k) view.Frame();  // past the hand-over at 0.5 s
  view.SetModeTarget(0, 0.15);
  for (int k = 0; k < 12; ++k) view.Frame();
  view.SetModeTarget(1, -0.1);
  for (int k = 0; k < 8; ++k) view.Frame();
  const std::string text = view.SessionScriptText();
  EXPECT_NE(text.find("keyframe"), std::string::npos) << text;
  EXPECT_NE(text.find("hold 0.1 0"), std::string::npos) << text;
  EXPECT_NE(text.find("set interp smooth"), std::string::npos) << text;
  ExpectReplayMatches(view, "view_keys_replay");
}

// A 3D object's script stopped at `keyframe`: the viewer draws it as a scene and plays its keys
// (the bend follows them, the body is placed, not pulled), then simulates on from their end,
// exactly as the interpreter's `keyframe` and `simul` do; the object goes on from the viewer's state.
TEST(InteractiveViewOfAScene, A3DObjectsKeysPlayFirstThenItSimulatesOn) {
  REQUIRE_DISPLAY();
  const std::string dir = testing::TempDir("view_keys3");
  const std::string script = dir + "/keys3.wob";
  std::ofstream(script) << "load_obj " << kData << "/table3.obj\nload_def " << kData << "/table3_modes.def3\n"
                        << "set integrator thesis\nset dt 0.01\nset_vec q 0 0 0 0 0 0 0 0 0 0\n"
                        << "key 0 bend=0\nkey 0.3 bend=0.2\nkey 0.5 bend=-0.1\n";
  const int bend = 6;  // q = (translation, rotation vector, bend, shear, squash, twist)
  std::ostringstream out;
  script::Interpreter interp(out);
  interp.RunFile(script);
  ViewerOptions options = TestOptions();
  options.keys_first = true;
  Eigen::VectorXd at_key2, at_keys_end, q;
  {
    InteractiveView view(interp.scene(), options);
    EXPECT_FALSE(view.character());
    view.Initialize();
    for (int k = 0; k < 9; ++k) view.Frame();  // 0.3 s: the second key
    at_key2 = view.world().coordinates(0);
    EXPECT_NEAR(at_key2[bend], 0.2, 1e-12);
    // right on a mass point: a keyframed body is placed, not pulled
    const Eigen::Vector3d on_point = view.WorldToDisplay(view.world().PointPosition(MassPointOf(0, 0)));
    EXPECT_FALSE(view.BeginDrag(int(std::lround(on_point[0])), int(std::lround(on_point[1]))));
    for (int k = 0; k < 6; ++k) view.Frame();  // 0.5 s: the keys' end
    EXPECT_NEAR(view.world().time(), 0.5, 1e-12);
    at_keys_end = view.world().coordinates(0);
    for (int k = 0; k < 15; ++k) view.Frame();  // 0.5 s more, simulated
    EXPECT_EQ(view.stats().steps, 100);
    q = view.world().coordinates(0);
    // once the body simulates, a press on a mass point picks it (so the refusal above meant something)
    const Eigen::Vector3d now = view.WorldToDisplay(view.world().PointPosition(MassPointOf(0, 0)));
    EXPECT_TRUE(view.BeginDrag(int(std::lround(now[0])), int(std::lround(now[1]))));
    view.EndDrag();
  }
  EXPECT_LT((interp.q() - q).cwiseAbs().maxCoeff(), 1e-15) << "the object goes on from the viewer's state";
  script::Interpreter ref(out);
  ref.RunFile(script);
  ref.RunLine("keyframe", "<test>", 1, dir);
  EXPECT_NEAR(ref.q()[bend], -0.1, 1e-12) << "the last key's bend";
  EXPECT_LT((ref.q() - at_keys_end).cwiseAbs().maxCoeff(), 1e-12) << "keyframe " << ref.q().transpose()
                                                                   << "\nviewer " << at_keys_end.transpose();
  ref.RunLine("simul 0.5", "<test>", 2, dir);
  EXPECT_LT((ref.q() - q).cwiseAbs().maxCoeff(), 1e-12) << "simul " << ref.q().transpose() << "\nviewer " << q.transpose();
  EXPECT_GT((q - at_keys_end).cwiseAbs().maxCoeff(), 1e-3) << "the body moves on after the keys";
}

TEST(InteractiveView, SessionWithADragSaysTheReplayStopsFollowing) {
  REQUIRE_DISPLAY();
  auto table = TableScene(Vec({0, 0, 0, 0, 0, 0, 0}));
  InteractiveView view(*table, TestOptions());
  view.Initialize();
  for (int k = 0; k < 5; ++k) view.Frame();
  const Eigen::Vector3d p = view.WorldToDisplay(WorldPositionOf(view.world(), 0, Eigen::Vector2d(0.5, 1.0)));
  ASSERT_TRUE(view.BeginDrag(int(p.x()), int(p.y())));
  view.DragTo(int(p.x()), int(p.y()) + 40);
  for (int k = 0; k < 5; ++k) view.Frame();
  view.EndDrag();
  EXPECT_NE(view.SessionScriptText().find("1 pull(s) by the mouse"), std::string::npos) << view.SessionScriptText();
  // a press far from the body picks nothing
  EXPECT_FALSE(view.BeginDrag(2, 499));
}

TEST(InteractiveView, RecordedPosesBecomeACyclicPoseGraphScript) {
  REQUIRE_DISPLAY();
  auto table = TableScene(Vec({0, 300, 0, 0, 0, 0, 0}));
  table->options().params.gravity_on = false;
  InteractiveView view(*table, TestOptions());
  view.Initialize();
  // the table in the air, free of the ground: the bend follows its target within ~2 s (K 4e6 on G ~ 1e7)
  std::vector<Eigen::VectorXd> amplitudes;
  view.SetModeTarget(0, 0.1);
  for (int k = 0; k < 60; ++k) view.Frame();
  amplitudes.push_back(view.world().q(0).tail(4));
  PressKey(&view, 'k');
  view.SetModeTarget(0, -0.1);
  for (int k = 0; k < 60; ++k) view.Frame();
  amplitudes.push_back(view.world().q(0).tail(4));
  PressKey(&view, 'k');
  const std::string dir = testing::TempDir("view_poses");
  const std::vector<std::string> files = view.SaveSession(dir + "/s.wob");
  ASSERT_EQ(files.size(), 2u);
  EXPECT_EQ(files[1], dir + "/s_poses.wob");
  std::ostringstream out;
  script::Interpreter interp(out);
  interp.RunFile(files[1]);  // parses and runs: 2 poses, 3 periods
  EXPECT_EQ(interp.pose_graph().poses.size(), 2u);
  EXPECT_TRUE(interp.pose_graph().cyclic);
  // the poses are the amplitudes at the key presses, exactly (shortest round-trip numbers)
  for (int i = 0; i < 2; ++i) EXPECT_EQ(interp.pose_graph().poses[i], amplitudes[i]);
  EXPECT_GT(amplitudes[0][0], 0.0);  // bent toward +0.1 when recorded
  EXPECT_LT(amplitudes[1][0], amplitudes[0][0]);
  EXPECT_NEAR(interp.pose_graph().durations[0], 2.0, 0.011);  // 60 frames of 1/30 s
}

// Runs a scene script up to its first `simul`, as `wobble view` does.
void RunUpToSimul(script::Interpreter* interp, const std::string& path) {
  std::ifstream in(path);
  ASSERT_TRUE(in) << path;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    std::istringstream words(line.substr(0, line.find('#')));
    std::string first;
    words >> first;
    if (first == "simul") return;
    interp->RunLine(line, path, number, kData);
  }
}

const std::string kFig2 = kData + "/fig2_triple_pendulum.wob";

TEST(InteractiveViewOfAScene, Fig2StepsTheScriptsSceneAsSimulDoes) {
  REQUIRE_DISPLAY();
  std::ostringstream log;
  script::Interpreter interp(log);
  RunUpToSimul(&interp, kFig2);
  ASSERT_TRUE(interp.scene().has_bodies());
  InteractiveView view(interp.scene(), TestOptions());
  view.Initialize();
  for (int k = 0; k < 30; ++k) view.Frame();  // 30 frames of 1/30 s: 1 s, 1000 steps of dt 0.001
  EXPECT_NEAR(view.time(), 1.0, 1e-9);
  EXPECT_EQ(view.stats().steps, 1000);
  const int pivot = interp.scene().Constraint("pivot");
  ASSERT_GE(pivot, 0);
  EXPECT_LT(view.world().ConstraintError(pivot).norm(), 1e-4);
  EXPECT_LT(view.world().MaxViolation(), 1e-4);
  // the pendulum has swung down from the horizontal
  EXPECT_LT(interp.scene().Point("tip")[1], -0.5);
  // an interpreter that runs `simul 1` itself ends in the same state
  std::ostringstream log2;
  script::Interpreter ref(log2);
  RunUpToSimul(&ref, kFig2);
  ref.RunLine("simul 1", "<test>", 1, kData);
  for (const char* name : {"elbow1", "elbow2", "tip"})
    EXPECT_LT((interp.scene().Point(name) - ref.scene().Point(name)).norm(), 1e-12) << name;
}

TEST(InteractiveViewOfAScene, DragTakesThePickedPointToTheCursorAndReleaseRemovesIt) {
  REQUIRE_DISPLAY();
  std::ostringstream log;
  script::Interpreter interp(log);
  RunUpToSimul(&interp, kFig2);
  InteractiveView view(interp.scene(), TestOptions());
  view.Initialize();
  // press on the tip (3, 0) and pull it to (2.5, -1), within reach of the nailed chain
  const Eigen::Vector3d press = view.WorldToDisplay(interp.scene().Point("tip"));
  const Eigen::Vector3d cursor_px = view.WorldToDisplay(Vec({2.5, -1.0}));
  Play(&view, Event("MouseMoveEvent", press.x(), press.y()) + Event("LeftButtonPressEvent", press.x(), press.y()) +
                  Event("MouseMoveEvent", cursor_px.x(), cursor_px.y()));
  ASSERT_TRUE(view.dragged_point().has_value()) << "the press did not pick a point";
  const int id = view.drag_constraint();
  ASSERT_GE(id, 0);
  EXPECT_EQ(view.world().constraint_kind(id), ConstraintKind::kTrajectory);
  const MaterialPoint picked = *view.dragged_point();
  EXPECT_LT((view.world().PointPosition(picked) - interp.scene().Point("tip")).norm(), 1e-12) << "not the tip";
  const Eigen::VectorXd target = view.drag_target();
  EXPECT_LT((target - Vec({2.5, -1.0})).norm(), 0.02) << "the cursor in the world: " << target.transpose();
  const double before = (view.world().PointPosition(picked) - target).norm();
  std::string frames;
  for (int k = 0; k < 15; ++k) frames += Event("TimerEvent", cursor_px.x(), cursor_px.y());
  Play(&view, frames);
  const double after = (view.world().PointPosition(picked) - target).norm();
  // the chain starts at rest, so the path is n(s) = c + A (1 + s/tau) e^(-s/tau) with
  // |A| = before (control::ApproachPath); after 15 frames (s = 0.5 s) the point is on it
  const double s = 0.5, tau = InteractiveView::kDragTime;
  EXPECT_GT(before, 0.9);
  EXPECT_NEAR(after, before * (1.0 + s / tau) * std::exp(-s / tau), 1e-4) << before << " -> " << after;
  EXPECT_LT(view.world().MaxViolation(), 1e-3);  // the nail and the joints hold meanwhile
  Play(&view, Event("LeftButtonReleaseEvent", cursor_px.x(), cursor_px.y()));
  EXPECT_FALSE(view.dragged_point().has_value());
  EXPECT_EQ(view.drag_constraint(), -1);
  EXPECT_FALSE(view.world().exists(id));
  // the chain falls again once let go
  const double y = view.world().PointPosition(picked)[1];
  Play(&view, frames);
  EXPECT_LT(view.world().PointPosition(picked)[1], y - 0.05);
}

// Pixels of the whole window within 20 (of 255) of a colour.
long CountColourEverywhere(vtkImageData* image, double r, double g, double b) {
  int dims[3];
  image->GetDimensions(dims);
  long n = 0;
  for (int y = 0; y < dims[1]; ++y)
    for (int x = 0; x < dims[0]; ++x) {
      const auto* p = static_cast<const unsigned char*>(image->GetScalarPointer(x, y, 0));
      if (std::abs(p[0] - r * 255) < 20 && std::abs(p[1] - g * 255) < 20 && std::abs(p[2] - b * 255) < 20) ++n;
    }
  return n;
}

TEST(InteractiveViewOfAScene, KeyTogglesTheAnchors) {
  REQUIRE_DISPLAY();
  std::ostringstream log;
  script::Interpreter interp(log);
  RunUpToSimul(&interp, kFig2);
  InteractiveView view(interp.scene(), TestOptions());
  view.Initialize();
  view.Frame();
  const double green[3] = {0.1, 0.55, 0.2};  // the anchors' colour (scene_view.cc)
  EXPECT_TRUE(view.LayerVisible(SceneLayer::kAnchors));
  const long shown = CountColourEverywhere(view.Capture(), green[0], green[1], green[2]);
  EXPECT_GT(shown, 20);
  PressKey(&view, 'a');
  EXPECT_FALSE(view.LayerVisible(SceneLayer::kAnchors));
  EXPECT_LT(CountColourEverywhere(view.Capture(), green[0], green[1], green[2]), shown / 10);
  PressKey(&view, 'a');
  EXPECT_TRUE(view.LayerVisible(SceneLayer::kAnchors));
  EXPECT_EQ(CountColourEverywhere(view.Capture(), green[0], green[1], green[2]), shown);
}

}  // namespace
}  // namespace wobble::pipelines
