// Pictures from Python through pipelines/ (VTK): a world drawn into a numpy image, and a
// recorded run rendered to files (PNG frames, filmstrip, .vtp/.pvd, EXR, charts) as
// `wobble render` does. VTK 9.1 renders only through X: without a display these raise.
#include "support.h"

#include <vtkImageData.h>
#include <vtkPointData.h>
#include <vtkUnsignedCharArray.h>

#include <cstring>

#include "pipelines/scene_view.h"
#include "pipelines/trajectory_render.h"
#include "wobble/core/errors.h"

namespace wobble::python {
namespace {

namespace pl = pipelines;

void RequireDisplay() {
  if (!pl::HasDisplay())
    throw std::runtime_error(
        "rendering needs an X display (VTK 9.1) and DISPLAY is unset or unreachable: run under\n"
        "  xvfb-run -a -s \"-screen 0 1280x1024x24\" python3 ...");
}

void CheckSize(int width, int height) {
  if (width < 16 || height < 16 || width > 8192 || height > 8192)
    throw InputError("width and height must be 16 to 8192 pixels, got " + std::to_string(width) + " x " +
                     std::to_string(height));
}

// (height, width, components) uint8, the top row first (VTK's images start at the bottom).
py::array_t<uint8_t> ToNumpy(vtkImageData* image) {
  int dims[3];
  image->GetDimensions(dims);
  const int w = dims[0], h = dims[1], c = image->GetNumberOfScalarComponents();
  py::array_t<uint8_t> out({py::ssize_t(h), py::ssize_t(w), py::ssize_t(c)});
  const auto* src = static_cast<const uint8_t*>(image->GetScalarPointer());
  uint8_t* dst = out.mutable_data();
  const size_t row = size_t(w) * size_t(c);
  for (int y = 0; y < h; ++y) std::memcpy(dst + size_t(y) * row, src + size_t(h - 1 - y) * row, row);
  return out;
}

pl::SceneOptions ViewOptions(int width, int height, bool lattice, bool points, bool shape, bool ground, bool overlay,
                             const std::string& color_by) {
  CheckSize(width, height);
  pl::SceneOptions o;
  o.width = width;
  o.height = height;
  o.show_lattice = lattice;
  o.show_points = points;
  o.show_shape = shape;
  o.show_ground = ground;
  o.overlay = overlay;
  o.color_by = color_by;
  return o;
}

}  // namespace

void BindRender(py::module_& m) {
  m.def("has_display", &pl::HasDisplay, "Whether VTK can render here (an X server answers on DISPLAY).");

  m.def(
      "render_world",
      [](const World& world, int width, int height, bool lattice, bool points, bool shape, bool ground, bool overlay,
         const std::string& color_by, const py::object& frame) {
        RequireDisplay();
        pl::SceneView view(&world, ViewOptions(width, height, lattice, points, shape, ground, overlay, color_by));
        if (frame.is_none()) {
          view.FrameBounds(pl::SceneBounds(world));
        } else {
          const auto box = frame.cast<std::vector<double>>();
          if (box.size() != 4 || !(box[2] > box[0]) || !(box[3] > box[1]))
            throw InputError("frame: expected (xmin, ymin, xmax, ymax) with xmax > xmin and ymax > ymin");
          view.FrameBox(Eigen::AlignedBox2d(Eigen::Vector2d(box[0], box[1]), Eigen::Vector2d(box[2], box[3])));
        }
        view.Render();
        return ToNumpy(view.Capture());
      },
      py::arg("world"), py::kw_only(), py::arg("width") = 640, py::arg("height") = 480, py::arg("lattice") = true,
      py::arg("points") = true, py::arg("shape") = true, py::arg("ground") = true, py::arg("overlay") = true,
      py::arg("color_by") = "", py::arg("frame") = py::none(),
      "The world now, drawn as `wobble render` draws a frame: an image (height, width, 3) of uint8,\n"
      "top row first. frame: (xmin, ymin, xmax, ymax) to show (None: every body and the ground).");

  m.def(
      "render",
      [](std::shared_ptr<record::Trajectory> run, const WorldOptions& options, const std::string& folder,
         const std::string& name, const std::vector<std::string>& what, double fps, int width, int height,
         const std::vector<double>& filmstrip_times, const std::string& color_by) {
        if (run->empty()) throw InputError("render: the trajectory has no samples");
        if (!(fps > 0) || fps > 1000) throw InputError("fps must be > 0 and at most 1000");
        pl::RenderOutputs out;
        out.folder = folder;
        out.name = name;
        const std::string error = pl::SetOutputs(what, &out);
        if (!error.empty()) throw InputError("what: " + error);
        if (out.frames || out.filmstrip || out.charts || out.exr) RequireDisplay();
        out.fps = fps;
        out.view = ViewOptions(width, height, true, true, true, true, true, color_by);
        out.view.title = name;
        out.filmstrip_times = filmstrip_times;
        World world = pl::WorldFor(*run, options);
        run->Restore(0, world);
        const pl::RenderReport report = pl::RenderTrajectory(world, *run, pl::SceneSpec{}, out);
        std::vector<std::string> files;
        for (const pl::RenderReport::File& f : report.files) files.push_back(f.path);
        return files;
      },
      py::arg("run"), py::arg("options"), py::arg("folder"), py::kw_only(), py::arg("name") = "run",
      py::arg("what") = std::vector<std::string>{"frames", "filmstrip", "vtp"}, py::arg("fps") = 30.0,
      py::arg("width") = 640, py::arg("height") = 480, py::arg("filmstrip_times") = std::vector<double>(),
      py::arg("color_by") = "",
      "Renders a recorded run into `folder` as `wobble render` does: what is any of frames,\n"
      "filmstrip, vtp (the ParaView .pvd series), charts, exr, disp, mp4 (name.mp4, H.264), webp\n"
      "(name.webp, animated), gltf (name.glb: the FFD bodies with a morph target per mode), web\n"
      "(web/index.html playing the .glb in a browser, opened from the disk; implies gltf); frames\n"
      "at `fps`. options: the\n"
      "world the run had (ground, gravity). Returns the paths written (frame series as patterns).");
}

}  // namespace wobble::python
