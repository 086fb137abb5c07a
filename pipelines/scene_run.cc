#include "pipelines/scene_run.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <vtkImageData.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>

#include "pipelines/exports.h"

namespace wobble::pipelines {
namespace {

template <class T> using Ptr = vtkSmartPointer<T>;

std::string Numbered(const std::string& folder, const std::string& stem, int frame, const char* ext) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "_%04d.%s", frame, ext);
  return folder + "/" + stem + buf;
}

// The .vtp parts of one body: three sources on the world that draws it.
struct BodyParts {
  std::vector<Ptr<vtkPolyDataAlgorithm>> sources;  // box/lattice, points, shape
  std::vector<std::string> names;
};

std::vector<BodyParts> MakeParts(const World& world, const ConstrainedSceneSpec& spec) {
  std::vector<BodyParts> parts;
  for (int b = 0; b < world.num_bodies(); ++b) {
    BodyParts p;
    const std::string stem = world.body_name(b).empty() ? "body" + std::to_string(b) : world.body_name(b);
    if (world.kind(b) == BodyKind::kLinear) {
      auto box = Ptr<LinearBoxSource>::New();
      auto points = Ptr<LinearMassPointSource>::New();
      auto shape = Ptr<LinearShapeSource>::New();
      if (b < int(spec.drawings.size())) shape->SetDrawing(spec.drawings[b]);
      for (ConstrainedSourceBase* s : {(ConstrainedSourceBase*)box, (ConstrainedSourceBase*)points, (ConstrainedSourceBase*)shape}) {
        s->SetWorld(&world);
        s->SetBody(b);
      }
      p.sources = {box, points, shape};
      p.names = {stem + "_box", stem + "_points", stem + "_shape"};
    } else {
      auto lattice = Ptr<LatticeSource>::New();
      auto points = Ptr<MassPointSource>::New();
      auto shape = Ptr<ShapeSource>::New();
      for (WorldSourceBase* s : {(WorldSourceBase*)lattice, (WorldSourceBase*)points, (WorldSourceBase*)shape}) {
        s->SetWorld(&world);
        s->SetBody(b);
      }
      p.sources = {lattice, points, shape};
      p.names = {stem + "_lattice", stem + "_points", stem + "_shape"};
    }
    parts.push_back(std::move(p));
  }
  return parts;
}

}  // namespace

ConstrainedSceneSpec SceneSpecOf(const std::vector<LinearDrawing>& drawings, const std::vector<control::Anchor>& anchors) {
  ConstrainedSceneSpec spec;
  spec.drawings = drawings;
  for (const control::Anchor& a : anchors) {
    AnchorSource::Anchor d;
    d.name = a.name;
    if (a.point) d.point = *a.point;
    d.place = a.place;
    spec.anchors.push_back(d);
  }
  return spec;
}

std::vector<std::string> WriteSceneRun(World& world, const ConstrainedSceneSpec& spec,
                                       const std::vector<record::SceneFrame>& frames, const SceneRunOutputs& out) {
  if (frames.empty()) throw std::invalid_argument("nothing was recorded: no frames to render");
  std::vector<std::string> written;

  // the camera frames every recorded state
  Eigen::AlignedBox3d motion;
  for (const record::SceneFrame& f : frames) {
    record::RestoreFrame(world, f);
    motion.extend(SceneBounds(world, spec));
  }
  const bool flat = IsFlat(world);
  auto frame_camera = [&](SceneView* v) {
    if (flat)
      v->FrameBox(Eigen::AlignedBox2d(motion.min().head<2>(), motion.max().head<2>()));
    else
      v->FrameBox3d(motion);
  };

  std::unique_ptr<SceneView> view, strip_view;
  if (out.frames) {
    SceneOptions o = out.view;
    o.width = out.width;
    o.height = out.height;
    view = std::make_unique<SceneView>(&world, spec, o);
    frame_camera(view.get());
  }
  // filmstrip panels: the recorded frame nearest each wanted time
  std::vector<size_t> strip_frames;
  if (out.filmstrip) {
    std::vector<double> times = out.filmstrip_times;
    if (times.empty())
      for (int k = 0; k < 6; ++k) times.push_back(frames.front().time + (frames.back().time - frames.front().time) * k / 5.0);
    for (double t : times) {
      size_t best = 0;
      for (size_t i = 0; i < frames.size(); ++i)
        if (std::abs(frames[i].time - t) < std::abs(frames[best].time - t)) best = i;
      strip_frames.push_back(best);
    }
    SceneOptions o = out.view;
    o.width = out.filmstrip_width;
    o.height = out.filmstrip_height;
    o.point_size = std::max(2.0, 0.6 * o.point_size);  // small panels: smaller dots
    o.overlay_energy = false;
    o.title.clear();
    strip_view = std::make_unique<SceneView>(&world, spec, o);
    frame_camera(strip_view.get());
  }
  std::vector<BodyParts> parts;
  PvdCollection pvd;
  const std::string vtp_folder = out.folder + "/vtp";
  if (out.vtp) parts = MakeParts(world, spec);

  std::vector<vtkSmartPointer<vtkImageData>> panels(strip_frames.size());
  for (size_t k = 0; k < frames.size(); ++k) {
    record::RestoreFrame(world, frames[k]);
    if (view) {
      view->Render();
      view->WritePng(Numbered(out.folder + "/frames", "frame", int(k), "png"));
    }
    for (size_t i = 0; i < strip_frames.size(); ++i)
      if (strip_frames[i] == k) {
        strip_view->Render();
        panels[i] = strip_view->Capture();
      }
    for (size_t b = 0; b < parts.size(); ++b)
      for (size_t j = 0; j < parts[b].sources.size(); ++j) {
        vtkPolyDataAlgorithm* src = parts[b].sources[j];
        src->Modified();
        src->Update();
        const std::string path = Numbered(vtp_folder, parts[b].names[j], int(k), "vtp");
        WriteVtp(path, src->GetOutput());
        pvd.Add(frames[k].time, int(3 * b + j), path, parts[b].names[j]);
      }
  }
  if (view) written.push_back(out.folder + "/frames/frame_NNNN.png");
  if (strip_view) {
    const std::string path = out.folder + "/filmstrip.png";
    WritePng(path, TileImages(panels, out.filmstrip_columns));
    written.push_back(path);
  }
  if (out.vtp) {
    const std::string path = vtp_folder + "/" + out.name + ".pvd";
    pvd.Write(path);
    written.push_back(path);
  }
  return written;
}

}  // namespace wobble::pipelines
