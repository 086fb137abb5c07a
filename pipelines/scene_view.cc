#include "pipelines/scene_view.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <thread>
#include <vtkActor.h>
#include <vtkCamera.h>
#include <vtkCellArray.h>
#include <vtkCoordinate.h>
#include <vtkDataArray.h>
#include <vtkFloatArray.h>
#include <vtkImageData.h>
#include <vtkLookupTable.h>
#include <vtkMatrix4x4.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkLight.h>
#include <vtkProperty.h>
#include <vtkRenderWindow.h>
#include <vtkRenderer.h>
#include <vtkScalarBarActor.h>
#include <vtkTextActor.h>
#include <vtkTriangleFilter.h>
#include <vtkTextProperty.h>
#include <vtkUnsignedCharArray.h>
#include <vtkWindowToImageFilter.h>

#include <X11/Xlib.h>  // after VTK: Xlib defines macros such as Status and Bool

#include "pipelines/exports.h"

namespace wobble::pipelines {

template <class T> using Ptr = vtkSmartPointer<T>;

bool HasDisplay() {
  // DISPLAY alone is not enough: a stale one (an X server that is gone) makes VTK abort, so
  // open a connection once and keep the answer. The probe connection stays open for the
  // life of the process: closing it made VTK's own XOpenDisplay fail now and then (seen
  // with Xvfb + Mesa here, about one process in three).
  static const bool has = [] {
    const char* d = std::getenv("DISPLAY");
    if (!d || !*d) return false;
    // Xvfb under a parallel ctest refuses a connection now and then: retry for about three
    // seconds before giving up (the tests then fail, since DISPLAY was set)
    static Display* probe = nullptr;
    for (int attempt = 0; attempt < 30 && !probe; ++attempt) {
      if (attempt > 0) std::this_thread::sleep_for(std::chrono::milliseconds(100));
      probe = XOpenDisplay(nullptr);
    }
    return probe != nullptr;
  }();
  return has;
}

Eigen::AlignedBox3d SceneBounds(const World& world, const SceneSpec& spec) {
  Eigen::AlignedBox3d box;
  for (int b = 0; b < world.num_bodies(); ++b) {
    if (world.kind(b) == BodyKind::kLinear) {
      const LinearDrawing* d = b < int(spec.drawings.size()) ? &spec.drawings[b] : nullptr;
      box.extend(LinearBodyBounds(world, b, d));
    } else {
      box.extend(FfdBodyBounds(world, b));
    }
  }
  return box;
}

bool IsFlat(const World& world) {
  for (int b = 0; b < world.num_bodies(); ++b)
    if (world.dim(b) != 2) return false;
  return true;
}

SceneSpec SceneSpecOf(const std::vector<LinearDrawing>& drawings, const std::vector<control::Anchor>& anchors) {
  SceneSpec spec;
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

struct SceneView::Impl {
  const World* world = nullptr;
  std::vector<Ptr<WorldSourceBase>> sources;  // re-run every Render() (the trails only on Record())
  Ptr<vtkRenderWindow> window;
  Ptr<vtkRenderer> renderer;
  Ptr<GroundSource> ground;
  Ptr<TrailSource> trails;
  // per body: the sources and mappers that color_by can colour
  std::vector<Ptr<MassPointSource>> points;
  std::vector<Ptr<LatticeSource>> lattices;
  std::vector<vtkPolyDataMapper*> colored;     // the mappers that show color_by
  std::vector<vtkPolyDataAlgorithm*> colored_sources;
  Ptr<vtkLookupTable> lut;
  Ptr<vtkScalarBarActor> bar;
  Ptr<vtkTextActor> overlay;
  Ptr<vtkImageData> last_rgb;                   // read back from the window after the last Render()
  std::vector<Ptr<vtkActor>> layers[7];         // by SceneLayer
  double z_scale = 1.0;  // 2D: z offsets keep points above lines above the ground; 3D: depth decides

  // An actor for `source` in `layer`, z_offset above the plane in 2D, flat colours unless lit.
  vtkActor* Add(SceneLayer layer, WorldSourceBase* source, const double rgb[3], double line_width, double point_size,
                double z_offset, bool lit = false) {
    auto mapper = Ptr<vtkPolyDataMapper>::New();
    mapper->SetInputConnection(source->GetOutputPort());
    mapper->ScalarVisibilityOff();
    auto actor = Ptr<vtkActor>::New();
    actor->SetMapper(mapper);
    actor->GetProperty()->SetColor(rgb[0], rgb[1], rgb[2]);
    actor->GetProperty()->SetLineWidth(float(line_width));
    actor->GetProperty()->SetPointSize(float(point_size));
    actor->GetProperty()->SetLighting(lit);
    actor->SetPosition(0, 0, z_offset * z_scale);
    renderer->AddActor(actor);
    layers[int(layer)].push_back(actor);
    if (source != trails.Get()) sources.push_back(source);
    return actor;
  }
};

SceneView::SceneView(const World* world, SceneOptions options, SceneSpec spec) : impl_(new Impl), options_(std::move(options)) {
  if (!HasDisplay())
    throw std::runtime_error("rendering needs an X display (VTK 9.1): run under xvfb-run -a -s \"-screen 0 1280x1024x24\"");
  if (!world) throw std::invalid_argument("SceneView: no world");
  if (options_.width < 16 || options_.height < 16 || options_.width > 8192 || options_.height > 8192)
    throw std::invalid_argument("image size must be between 16 and 8192 pixels a side");
  Impl& m = *impl_;
  m.world = world;
  m.z_scale = IsFlat(*world) ? 1.0 : 0.0;
  const bool clean = options_.style == RenderStyle::kClean;
  if (clean) options_.show_lattice = options_.show_points = false;
  SetUpWindow();
  if (clean) m.renderer->UseFXAAOn();  // anti-aliased lines and edges, offscreen too

  const double ground_rgb[3] = {0.55, 0.47, 0.38}, lattice_rgb[3] = {0.45, 0.6, 0.85}, shape_rgb[3] = {0.1, 0.1, 0.1},
               surface_rgb[3] = {0.95, 0.75, 0.35}, points_rgb[3] = {0.85, 0.2, 0.15}, spring_rgb[3] = {0.2, 0.6, 0.2},
               trail_rgb[3] = {0.6, 0.3, 0.7}, anchor_rgb[3] = {0.1, 0.55, 0.2};
  auto on = [&](WorldSourceBase* s, int body) {
    s->SetWorld(world);
    s->SetBody(body);
    return s;
  };
  // the world's layers, where FFD bodies live: ground, trails, springs
  int first_ffd[4] = {-1, -1, -1, -1}, ground_dim = 0;  // by dimension; ground_dim: GroundDimensionOf the bodies
  for (int b = world->num_bodies() - 1; b >= 0; --b) {
    if (world->kind(b) == BodyKind::kFfd) first_ffd[world->dim(b)] = b;
    ground_dim = std::max(ground_dim, GroundDimensionOf(*world, b));
  }
  if (first_ffd[3] >= 0 || ground_dim == 3) {
    // a light from above besides the camera's: the camera's alone leaves every upward face
    // (a table's top, the ground) dark at a low elevation
    auto head = Ptr<vtkLight>::New();
    head->SetLightTypeToHeadlight();
    head->SetIntensity(0.75);
    auto sky = Ptr<vtkLight>::New();
    sky->SetLightTypeToSceneLight();
    sky->SetPositional(false);
    sky->SetPosition(0.3, 1.0, 0.5);
    sky->SetFocalPoint(0.0, 0.0, 0.0);
    sky->SetIntensity(0.5);
    m.renderer->AddLight(head);
    m.renderer->AddLight(sky);
  }
  if (ground_dim == 3) {  // the 3D ground plane, lit, several body sizes across
    m.ground = Ptr<GroundSource>::New();
    const Eigen::AlignedBox3d box = SceneBounds(*world, spec);
    m.ground->SetLength(6.0 * box.sizes().maxCoeff());
    const double plane_rgb[3] = {0.78, 0.74, 0.66};
    vtkProperty* plane = m.Add(SceneLayer::kGround, on(m.ground, 0), plane_rgb, 1.0, 1.0, 0.0, true)->GetProperty();
    plane->SetAmbient(0.55);  // the camera's light grazes the plane: mostly ambient, or it goes black
    plane->SetDiffuse(0.45);
  }
  if (ground_dim == 2) {
    m.ground = Ptr<GroundSource>::New();
    m.Add(SceneLayer::kGround, on(m.ground, 0), ground_rgb, 1.0, 1.0, 0.0);
  }
  if (first_ffd[2] >= 0) {  // trails of lattice coordinates (s, t): 2D bodies
    m.trails = Ptr<TrailSource>::New();
    m.Add(SceneLayer::kTrails, on(m.trails, first_ffd[2]), trail_rgb, 1.5, 1.0, 0.5);
  }
  if (first_ffd[2] >= 0 || first_ffd[3] >= 0)  // springs of either dimension (SpringSource)
    m.Add(SceneLayer::kSprings, on(Ptr<SpringSource>::New(), 0), spring_rgb, 1.5, 1.0, 1.5);
  // every body: lattice (or control box), shape, mass points
  std::vector<vtkPolyDataMapper*> point_mappers, lattice_mappers;
  for (int b = 0; b < world->num_bodies(); ++b) {
    m.lattices.push_back(Ptr<LatticeSource>::New());
    m.points.push_back(Ptr<MassPointSource>::New());
    lattice_mappers.push_back(vtkPolyDataMapper::SafeDownCast(
        m.Add(SceneLayer::kLattice, on(m.lattices[b], b), lattice_rgb, 1.0, options_.point_size * 0.75, 1)->GetMapper()));
    if (world->IsFfd(b, 2)) {
      if (clean) {  // closed outlines filled under the lines; VTK fans polygons, so triangulated
        auto fill = Ptr<ShapeSource>::New();
        fill->SetSamplesPerSegment(options_.shape_samples);
        fill->SetFillClosed(true);
        auto triangles = Ptr<vtkTriangleFilter>::New();
        triangles->SetInputConnection(on(fill, b)->GetOutputPort());
        m.Add(SceneLayer::kShape, fill, surface_rgb, 1.0, 1.0, 1.5)->GetMapper()->SetInputConnection(
            triangles->GetOutputPort());
      }
      auto shape = Ptr<ShapeSource>::New();
      shape->SetSamplesPerSegment(options_.shape_samples);
      m.Add(SceneLayer::kShape, on(shape, b), shape_rgb, clean ? 2.0 * options_.line_width : options_.line_width, 1.0, 2);
    } else if (world->IsFfd(b, 3)) {
      // the mesh as a lit surface (flat-shaded facets), and the polylines over it
      auto surface = Ptr<ShapeSource>::New();
      surface->SetLines(false);
      m.Add(SceneLayer::kShape, on(surface, b), surface_rgb, 1.0, 1.0, 0.0, true);
      auto lines = Ptr<ShapeSource>::New();
      lines->SetSurface(false);
      lines->SetSamplesPerSegment(options_.shape_samples);
      m.Add(SceneLayer::kShape, on(lines, b), shape_rgb, options_.line_width, 1.0, 0.0);
    } else if (b < int(spec.drawings.size()) && spec.drawings[b].dim() != 0) {
      const LinearDrawing& d = spec.drawings[b];
      if (!d.triangles.empty()) {
        // a lit, slightly transparent surface under the outline so the mass points show through
        auto surface = Ptr<ShapeSource>::New();
        surface->SetDrawing(d);
        surface->SetLines(false);
        m.Add(SceneLayer::kShape, on(surface, b), surface_rgb, 1.0, 1.0, 0.5, true)->GetProperty()->SetOpacity(0.55);
      }
      auto lines = Ptr<ShapeSource>::New();
      lines->SetDrawing(d);
      lines->SetSurface(false);
      m.Add(SceneLayer::kShape, on(lines, b), shape_rgb, options_.line_width, 1.0, 2);
    }
    // a mesh's sampled mass (hundreds of points) would cover its surface at the usual size
    double point_size = options_.point_size;
    if (world->IsFfd(b, 3))
      point_size = std::max(2.0, point_size * std::min(1.0, std::sqrt(27.0 / world->body<3>(b).num_points())));
    point_mappers.push_back(vtkPolyDataMapper::SafeDownCast(
        m.Add(SceneLayer::kPoints, on(m.points[b], b), points_rgb, 1.0, point_size, 3)->GetMapper()));
  }
  if (!spec.anchors.empty()) {
    auto anchors = Ptr<AnchorSource>::New();
    anchors->SetAnchors(spec.anchors);
    m.Add(SceneLayer::kAnchors, on(anchors, 0), anchor_rgb, 1.0, options_.point_size * 1.6, 4);
  }
  // every layer has its actors; the show_* options only set whether they start visible
  SetLayerVisible(SceneLayer::kGround, options_.show_ground);
  SetLayerVisible(SceneLayer::kTrails, options_.show_trails);
  SetLayerVisible(SceneLayer::kLattice, options_.show_lattice);
  SetLayerVisible(SceneLayer::kSprings, options_.show_springs);
  SetLayerVisible(SceneLayer::kShape, options_.show_shape);
  SetLayerVisible(SceneLayer::kPoints, options_.show_points);

  // colour by an array: a mass-point array, or the lattice's displacement
  if (!options_.color_by.empty()) {
    const bool on_lattice = options_.color_by == "displacement";
    static const char* kPointArrays[] = {"mass", "velocity", "applied_force", "in_contact"};
    const bool known = on_lattice || std::any_of(std::begin(kPointArrays), std::end(kPointArrays),
                                                 [&](const char* a) { return options_.color_by == a; });
    if (!known)
      throw std::invalid_argument("color by '" + options_.color_by +
                                  "': not one of mass, velocity, applied_force, in_contact, displacement");
    if (!(on_lattice ? options_.show_lattice : options_.show_points) || world->num_bodies() == 0)
      throw std::invalid_argument("color by '" + options_.color_by + "': that layer is hidden");
    m.colored = on_lattice ? lattice_mappers : point_mappers;
    for (int b = 0; b < world->num_bodies(); ++b)
      m.colored_sources.push_back(on_lattice ? static_cast<vtkPolyDataAlgorithm*>(m.lattices[b].Get()) : m.points[b].Get());
    m.lut = Ptr<vtkLookupTable>::New();
    m.lut->SetHueRange(0.667, 0.0);  // blue (low) to red (high)
    m.lut->SetVectorModeToMagnitude();
    m.lut->Build();
    for (vtkPolyDataMapper* mapper : m.colored) {
      mapper->ScalarVisibilityOn();
      mapper->SetScalarModeToUsePointFieldData();
      mapper->SelectColorArray(options_.color_by.c_str());
      mapper->SetColorModeToMapScalars();
      mapper->SetLookupTable(m.lut);
      mapper->UseLookupTableScalarRangeOn();
    }
    if (options_.show_color_bar) {
      m.bar = Ptr<vtkScalarBarActor>::New();
      m.bar->SetLookupTable(m.lut);
      m.bar->SetTitle(options_.color_by.c_str());
      m.bar->SetNumberOfLabels(3);
      m.bar->SetOrientationToHorizontal();
      m.bar->SetPosition(0.62, 0.86);
      m.bar->SetWidth(0.36);
      m.bar->SetHeight(0.12);
      m.bar->GetTitleTextProperty()->SetColor(0, 0, 0);
      m.bar->GetLabelTextProperty()->SetColor(0, 0, 0);
      m.bar->GetTitleTextProperty()->ShadowOff();
      m.bar->GetLabelTextProperty()->ShadowOff();
      m.renderer->AddActor2D(m.bar);
    }
  }
  SetUpOverlay();
  FrameBounds(SceneBounds(*world, spec));
}

void SceneView::SetUpWindow() {
  Impl& m = *impl_;
  m.renderer = Ptr<vtkRenderer>::New();
  m.renderer->SetBackground(1.0, 1.0, 1.0);
  m.window = Ptr<vtkRenderWindow>::New();
  m.window->SetOffScreenRendering(options_.offscreen ? 1 : 0);
  m.window->SetMultiSamples(0);  // identical pixels run to run, cheaper readback
  m.window->SetSize(options_.width, options_.height);
  m.window->AddRenderer(m.renderer);
  const double* vp = options_.viewport;
  if (!(vp[0] >= 0 && vp[1] >= 0 && vp[2] <= 1 && vp[3] <= 1 && vp[0] < vp[2] && vp[1] < vp[3]))
    throw std::invalid_argument("SceneView: the viewport must lie inside [0, 1] x [0, 1]");
  m.renderer->SetViewport(vp[0], vp[1], vp[2], vp[3]);
}

void SceneView::SetUpOverlay() {
  Impl& m = *impl_;
  if (options_.overlay || !options_.title.empty()) {
    m.overlay = Ptr<vtkTextActor>::New();
    m.overlay->GetTextProperty()->SetColor(0, 0, 0);
    m.overlay->GetTextProperty()->SetFontSize(std::max(10, options_.height / 32));
    m.overlay->GetTextProperty()->SetFontFamilyToCourier();
    m.overlay->GetTextProperty()->SetVerticalJustificationToTop();
    m.overlay->SetDisplayPosition(int(options_.viewport[0] * options_.width) + 8,
                                  int(options_.viewport[3] * options_.height) - 8);
    m.renderer->AddActor2D(m.overlay);
  }
}

void SceneView::FrameBounds(const Eigen::AlignedBox3d& box, double margin) {
  if (IsFlat(*impl_->world))
    FrameBox(box.isEmpty() ? Eigen::AlignedBox2d() : Eigen::AlignedBox2d(box.min().head<2>(), box.max().head<2>()), margin);
  else
    FrameBox3d(box, margin);
}

void SceneView::FrameBox3d(const Eigen::AlignedBox3d& box_in, double margin) {
  Eigen::AlignedBox3d box = box_in;
  if (box.isEmpty()) box = Eigen::AlignedBox3d(Eigen::Vector3d(-1, -1, -1), Eigen::Vector3d(1, 1, 1));
  const double az = options_.azimuth * M_PI / 180.0, el = options_.elevation * M_PI / 180.0;
  // the camera looks at the box's centre from direction `dir`; right and up span the image
  const Eigen::Vector3d dir(std::cos(el) * std::sin(az), std::sin(el), std::cos(el) * std::cos(az));
  const Eigen::Vector3d right = Eigen::Vector3d::UnitY().cross(dir).normalized();
  const Eigen::Vector3d up = dir.cross(right);
  const double aspect = double(options_.width) / options_.height;
  const double tan_v = std::tan(0.5 * options_.view_angle * M_PI / 180.0) / (1.0 + 2.0 * margin);
  const double tan_h = tan_v * aspect;
  // the nearest distance that keeps every corner of the box inside the view: a corner at
  // offset r from the centre is at depth d − r·dir and must have |r·right| <= depth tan_h and
  // |r·up| <= depth tan_v
  // |r·up| <= depth tan_v. Then the focal point moves so the box's image is centred (a box
  // seen from above projects lower than its centre), and the distance is fitted again.
  Eigen::Vector3d c = box.center();
  double distance = 1e-6;
  for (int pass = 0; pass < 3; ++pass) {
    distance = 1e-6;
    for (int k = 0; k < 8; ++k) {
      const Eigen::Vector3d r = box.corner(Eigen::AlignedBox3d::CornerType(k)) - c;
      distance = std::max({distance, r.dot(dir) + std::abs(r.dot(right)) / tan_h, r.dot(dir) + std::abs(r.dot(up)) / tan_v});
    }
    if (pass == 2) break;
    Eigen::Vector2d lo(1e300, 1e300), hi(-1e300, -1e300);
    for (int k = 0; k < 8; ++k) {
      const Eigen::Vector3d r = box.corner(Eigen::AlignedBox3d::CornerType(k)) - c;
      const double depth = distance - r.dot(dir);
      const Eigen::Vector2d screen(r.dot(right) / depth, r.dot(up) / depth);  // tangents of the angles
      lo = lo.cwiseMin(screen);
      hi = hi.cwiseMax(screen);
    }
    const Eigen::Vector2d mid = 0.5 * (lo + hi);
    c += distance * (mid.x() * right + mid.y() * up);
  }
  const double radius = 0.5 * box.sizes().norm();
  const Eigen::Vector3d eye = c + distance * dir;
  vtkCamera* cam = impl_->renderer->GetActiveCamera();
  cam->ParallelProjectionOff();
  cam->SetViewAngle(options_.view_angle);
  cam->SetFocalPoint(c.x(), c.y(), c.z());
  cam->SetPosition(eye.x(), eye.y(), eye.z());
  cam->SetViewUp(0, 1, 0);
  cam->SetClippingRange(std::max(1e-3 * distance, distance - 1.5 * radius), distance + 1.5 * radius);
  // what the frame shows in the plane through the centre facing the camera, for callers
  const double half_h = distance * std::tan(0.5 * options_.view_angle * M_PI / 180.0);
  framed_ = Eigen::AlignedBox2d(c.head<2>() - Eigen::Vector2d(half_h * aspect, half_h),
                                c.head<2>() + Eigen::Vector2d(half_h * aspect, half_h));
}

SceneView::~SceneView() = default;

void SceneView::FrameBox(const Eigen::AlignedBox2d& box_in, double margin) {
  Eigen::AlignedBox2d box = box_in;
  if (box.isEmpty()) box = Eigen::AlignedBox2d(Eigen::Vector2d(-1, -1), Eigen::Vector2d(1, 1));
  const Eigen::Vector2d c = box.center();
  Eigen::Vector2d half = 0.5 * box.sizes() * (1.0 + 2.0 * margin);
  half = half.cwiseMax(1e-6);
  // the renderer's part of the window
  const double* vp = options_.viewport;
  const double aspect = double(options_.width) * (vp[2] - vp[0]) / (options_.height * (vp[3] - vp[1]));
  // parallel scale is half the visible height: fit both the box's height and its width
  const double scale = std::max(half.y(), half.x() / aspect);
  framed_ = Eigen::AlignedBox2d(c - Eigen::Vector2d(scale * aspect, scale), c + Eigen::Vector2d(scale * aspect, scale));
  vtkCamera* cam = impl_->renderer->GetActiveCamera();
  cam->ParallelProjectionOn();
  const double distance = 10.0 * scale + 100.0;
  cam->SetFocalPoint(c.x(), c.y(), 0.0);
  cam->SetPosition(c.x(), c.y(), distance);
  cam->SetViewUp(0, 1, 0);
  cam->SetParallelScale(scale);
  cam->SetClippingRange(distance - 10.0, distance + 10.0);
  // the ground band: as long as the view is wide, reaching below its bottom edge
  if (impl_->ground) {
    impl_->ground->SetCenter(c.x(), c.y());
    impl_->ground->SetLength(4.0 * scale * aspect + 4.0 * scale);
    impl_->ground->SetDepth(4.0 * scale);
  }
}

void SceneView::Render() {
  Impl& m = *impl_;
  for (WorldSourceBase* s : m.sources) s->Modified();
  if (!m.colored.empty()) {
    double lo = options_.color_range[0], hi = options_.color_range[1];
    if (!(lo < hi)) {
      double r[2];
      ColorRangeNow(r);
      lo = r[0];
      hi = r[1] > r[0] ? r[1] : r[0] + 1.0;
    }
    m.lut->SetTableRange(lo, hi);
  }
  if (m.overlay) {
    std::string text = options_.title.empty() ? "" : options_.title + "\n";
    if (options_.overlay) {
      char buf[256];
      std::snprintf(buf, sizeof(buf), "t = %.3f s", m.world->time());
      text += buf;
      if (!caption_.empty()) text += "   " + caption_;
      if (options_.overlay_energy) {
        // E and every term of it that is not zero (ground and springs only when they hold
        // energy), so that E is the sum of the terms listed; two to a line, to stay narrow
        Energies sum;
        for (int b = 0; b < m.world->num_bodies(); ++b) {
          const Energies e = m.world->ComputeEnergies(b);
          sum.kinetic += e.kinetic;
          sum.gravity += e.gravity;
          sum.modes += e.modes;
          sum.ground += e.ground;
          sum.springs += e.springs;
        }
        std::snprintf(buf, sizeof(buf), "\nE = %.4g =", sum.total());
        text += buf;
        const std::pair<const char*, double> terms[] = {
            {"kin", sum.kinetic}, {"grav", sum.gravity}, {"modes", sum.modes}, {"ground", sum.ground}, {"springs", sum.springs}};
        int listed = 0;
        for (const auto& [name, value] : terms) {
          if (value == 0.0 && listed >= 3) continue;  // kin, grav and modes always
          text += listed % 2 == 0 ? "\n  " : " ";
          if (listed > 0) text += "+ ";
          std::snprintf(buf, sizeof(buf), "%s %.3g", name, value);
          text += buf;
          ++listed;
        }
      }
    }
    m.overlay->SetInput(text.c_str());
  }
  if (m.bar) {  // the colour bar top right, or bottom right when the text reaches under it
    const double at_top[2] = {0.62, 0.86}, at_bottom[2] = {0.62, 0.02};
    const double* where = at_top;
    if (m.overlay) {
      double text_box[4];  // xmin, xmax, ymin, ymax relative to the text's position: made absolute
      m.overlay->GetBoundingBox(m.renderer, text_box);
      const int* at = m.overlay->GetPositionCoordinate()->GetComputedDisplayValue(m.renderer);
      for (int k = 0; k < 4; ++k) text_box[k] += at[k / 2];
      const int* size = m.renderer->GetSize();
      const int* origin = m.renderer->GetOrigin();
      const double bar_x0 = origin[0] + at_top[0] * size[0], bar_x1 = bar_x0 + m.bar->GetWidth() * size[0];
      const double bar_y0 = origin[1] + at_top[1] * size[1], bar_y1 = bar_y0 + m.bar->GetHeight() * size[1];
      if (text_box[0] < bar_x1 && text_box[1] > bar_x0 && text_box[2] < bar_y1 && text_box[3] > bar_y0) where = at_bottom;
    }
    m.bar->SetPosition(where[0], where[1]);
  }
  m.window->Render();
  m.last_rgb = nullptr;
}

vtkSmartPointer<vtkImageData> ReadWindowRgb(vtkRenderWindow* window, bool rerender) {
  auto grab = Ptr<vtkWindowToImageFilter>::New();
  grab->SetInput(window);
  grab->SetInputBufferTypeToRGB();
  grab->ReadFrontBufferOff();
  grab->SetShouldRerender(rerender);
  grab->Update();
  auto image = Ptr<vtkImageData>::New();
  image->DeepCopy(grab->GetOutput());
  return image;
}

vtkSmartPointer<vtkImageData> SceneView::Capture() {
  if (!impl_->last_rgb) impl_->last_rgb = ReadWindowRgb(impl_->window);
  return impl_->last_rgb;
}

void SceneView::WritePng(const std::string& path, BackgroundWriter* writer) {
  const int level = options_.png_compression;
  if (!writer) return pipelines::WritePng(path, Capture(), level);
  // the pixels are copied out here: VTK objects never reach the worker threads
  writer->Submit([path, pixels = PixelsOf(Capture()), level] { WritePngPixels(path, pixels, level); });
}

ExrFrame SceneView::CaptureExrFrame() {
  const int w = options_.width, h = options_.height;
  vtkImageData* rgb = Capture();
  auto z = Ptr<vtkFloatArray>::New();
  impl_->window->GetZbufferData(0, 0, w - 1, h - 1, z);
  int dims[3];
  rgb->GetDimensions(dims);
  if (dims[0] != w || dims[1] != h || rgb->GetNumberOfScalarComponents() != 3 || z->GetNumberOfValues() != vtkIdType(w) * h)
    throw std::runtime_error("reading the rendered pixels back failed");
  // window depth d in [0, 1] is linear in the eye distance for a parallel projection:
  // distance = near + d (far − near); in perspective (3D views) it is hyperbolic:
  // distance = n f / (f − d (f − n)). The far plane (d = 1) means nothing was drawn.
  double range[2];
  impl_->renderer->GetActiveCamera()->GetClippingRange(range);
  const bool parallel = impl_->renderer->GetActiveCamera()->GetParallelProjection() != 0;
  auto eye_distance = [&](double d) {
    return parallel ? range[0] + d * (range[1] - range[0]) : range[0] * range[1] / (range[1] - d * (range[1] - range[0]));
  };
  // the colour stays sRGB-encoded here (ExrFrameChannels decodes it on a writer thread); rows
  // are flipped to top first by copies and plain per-row loops, no per-pixel push_back: this
  // runs on the render thread, which the writer threads wait for
  ExrFrame f;
  f.width = w;
  f.height = h;
  const size_t n = size_t(w) * h;
  const auto* px = static_cast<const unsigned char*>(rgb->GetScalarPointer());
  const float* zp = z->GetPointer(0);
  const float inf = std::numeric_limits<float>::infinity();
  f.srgb.resize(3 * n);
  f.depth.resize(n);
  f.overlay.resize(n);
  for (int y = h - 1, out = 0; y >= 0; --y, out += w) {  // VTK's rows start at the bottom
    const float* zr = zp + size_t(y) * w;
    std::memcpy(f.srgb.data() + 3 * size_t(out), px + 3 * size_t(y) * w, 3 * size_t(w));
    float* depth = f.depth.data() + out;
    uint8_t* overlay = f.overlay.data() + out;
    // VTK draws the 2D overlay (text, colour bar) at window depth 0, the near plane, which no
    // geometry reaches (the cameras keep the near plane in front of everything framed): those
    // pixels are the overlay's, in no layer of the EXR
    for (int x = 0; x < w; ++x) overlay[x] = zr[x] == 0.0f;
    for (int x = 0; x < w; ++x) depth[x] = zr[x] < 1.0f && zr[x] > 0.0f ? float(eye_distance(zr[x])) : inf;
  }
  f.characters = CharacterGeometry();
  f.metadata = ExrCameraMetadata();
  f.terrain_layer = options_.exr_terrain_layer;
  f.nuke_motion = options_.exr_nuke_motion;
  f.blender_motion = options_.exr_blender_motion;
  return f;
}

ScreenGeometry SceneView::CharacterGeometry() const {
  Impl& m = *impl_;
  const int* size = m.window->GetSize();
  const double* vp = m.renderer->GetViewport();
  const double x0 = vp[0] * size[0], y0 = vp[1] * size[1], pw = (vp[2] - vp[0]) * size[0], ph = (vp[3] - vp[1]) * size[1];
  // world to clip coordinates (VTK's normalised view: x, y, z in [−1, 1] after the divide)
  vtkCamera* camera = m.renderer->GetActiveCamera();
  vtkMatrix4x4* projection = camera->GetCompositeProjectionTransformMatrix(pw / ph, -1, 1);
  Eigen::Matrix4d clip_of_world;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) clip_of_world(i, j) = projection->GetElement(i, j);
  ScreenGeometry g;
  for (SceneLayer layer : {SceneLayer::kShape, SceneLayer::kLattice, SceneLayer::kPoints})
    for (const Ptr<vtkActor>& actor : m.layers[int(layer)]) {
      if (!actor->GetVisibility()) continue;
      vtkPolyData* pd = vtkPolyData::SafeDownCast(actor->GetMapper()->GetInput());
      if (!pd || !pd->GetPoints()) continue;
      Eigen::Matrix4d model;  // the actor's own offset (2D layers are lifted along z)
      vtkMatrix4x4* am = actor->GetMatrix();
      for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) model(i, j) = am->GetElement(i, j);
      const Eigen::Matrix4d to_clip = clip_of_world * model;
      const int first = int(g.vertices.size());
      const vtkIdType n = pd->GetNumberOfPoints();
      for (vtkIdType i = 0; i < n; ++i) {
        double p[3];
        pd->GetPoint(i, p);
        const Eigen::Vector4d c = to_clip * Eigen::Vector4d(p[0], p[1], p[2], 1.0);
        g.vertices.emplace_back(x0 + 0.5 * (c.x() / c.w() + 1.0) * pw, y0 + 0.5 * (c.y() / c.w() + 1.0) * ph,
                                0.5 * (c.z() / c.w() + 1.0));
        g.w.push_back(c.w());
      }
      g.groups.push_back(int(n));
      const double line_width = actor->GetProperty()->GetLineWidth(), point_size = actor->GetProperty()->GetPointSize();
      vtkIdType count;
      const vtkIdType* ids;
      for (pd->GetVerts()->InitTraversal(); pd->GetVerts()->GetNextCell(count, ids);)
        for (vtkIdType k = 0; k < count; ++k) g.dots.push_back({first + int(ids[k]), point_size});
      for (pd->GetLines()->InitTraversal(); pd->GetLines()->GetNextCell(count, ids);)
        for (vtkIdType k = 0; k + 1 < count; ++k) g.segments.push_back({first + int(ids[k]), first + int(ids[k + 1]), line_width});
      for (pd->GetPolys()->InitTraversal(); pd->GetPolys()->GetNextCell(count, ids);)  // fans, as VTK draws them
        for (vtkIdType k = 1; k + 1 < count; ++k)
          g.triangles.push_back({first + int(ids[0]), first + int(ids[k]), first + int(ids[k + 1])});
      for (pd->GetStrips()->InitTraversal(); pd->GetStrips()->GetNextCell(count, ids);)
        for (vtkIdType k = 0; k + 2 < count; ++k)
          g.triangles.push_back({first + int(ids[k]), first + int(ids[k + 1]), first + int(ids[k + 2])});
    }
  return g;
}

ExrMetadata SceneView::ExrCameraMetadata() const {
  vtkCamera* camera = impl_->renderer->GetActiveCamera();
  auto eigen = [](vtkMatrix4x4* m) {
    Eigen::Matrix4d e;
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) e(i, j) = m->GetElement(i, j);
    return e;
  };
  // VTK's camera space is right-handed looking along −z; OpenEXR's (RenderMan's) is left-handed
  // looking along +z: z flips
  const Eigen::Matrix4d to_camera = Eigen::Vector4d(1, 1, -1, 1).asDiagonal() * eigen(camera->GetViewTransformMatrix());
  // VTK's NDC is [−1, 1]² with y up; OpenEXR's [0, 1]² from the top left
  Eigen::Matrix4d to_exr_ndc;
  to_exr_ndc << 0.5, 0, 0, 0.5, 0, -0.5, 0, 0.5, 0, 0, 1, 0, 0, 0, 0, 1;
  const double aspect = double(options_.width) / double(options_.height);
  const Eigen::Matrix4d to_ndc = to_exr_ndc * eigen(camera->GetCompositeProjectionTransformMatrix(aspect, -1, 1));
  // OpenEXR multiplies row vectors (p' = p M): the transposes, row-major
  auto rows = [](const Eigen::Matrix4d& column_form) {
    std::array<float, 16> a;
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) a[size_t(4 * i + j)] = float(column_form(j, i));
    return a;
  };
  ExrMetadata m;
  m.world_to_camera = rows(to_camera);
  m.world_to_ndc = rows(to_ndc);
  return m;
}

void SceneView::WriteExr(const std::string& path, BackgroundWriter* writer, double fps, long frame) {
  const ExrCompression compression = options_.exr_compression;
  ExrFrame f = CaptureExrFrame();
  f.metadata.frames_per_second = fps;
  f.metadata.frame = frame;
  if (!writer) return WriteExrFrame(path, f, nullptr, nullptr, compression);
  writer->Submit([path, compression, f = std::move(f)] { WriteExrFrame(path, f, nullptr, nullptr, compression); });
}

bool SceneView::ColorRangeNow(double range[2]) {
  range[0] = 0.0;
  range[1] = 1.0;
  double lo = 1e300, hi = -1e300;
  for (vtkPolyDataAlgorithm* src : impl_->colored_sources) {
    src->Modified();
    src->Update();
    vtkDataArray* a = src->GetOutput()->GetPointData()->GetArray(options_.color_by.c_str());
    if (!a) continue;
    double r[2];
    a->GetRange(r, a->GetNumberOfComponents() > 1 ? -1 : 0);  // magnitude for vectors
    lo = std::min(lo, r[0]);
    hi = std::max(hi, r[1]);
  }
  if (!(lo <= hi)) return false;
  range[0] = lo;
  range[1] = hi;
  return true;
}

void SceneView::SetColorRange(double lo, double hi) {
  options_.color_range[0] = lo;
  options_.color_range[1] = hi;
}

void SceneView::SetLayerVisible(SceneLayer layer, bool visible) {
  for (vtkActor* a : impl_->layers[int(layer)]) a->SetVisibility(visible);
}
bool SceneView::LayerVisible(SceneLayer layer) const {
  const auto& actors = impl_->layers[int(layer)];
  return !actors.empty() && actors.front()->GetVisibility() != 0;  // a layer the view does not draw: hidden
}

void SceneView::SetWorld(const World* world) {
  if (!world || world->num_bodies() != impl_->world->num_bodies())
    throw std::invalid_argument("SceneView::SetWorld: not a world of the same bodies");
  Impl& m = *impl_;
  m.world = world;
  for (WorldSourceBase* s : m.sources) s->SetWorld(world);
  if (m.trails) m.trails->SetWorld(world);
}

TrailSource* SceneView::trails() { return impl_->trails; }
vtkRenderWindow* SceneView::window() { return impl_->window; }
vtkRenderer* SceneView::renderer() { return impl_->renderer; }

vtkSmartPointer<vtkImageData> TileImages(const std::vector<vtkSmartPointer<vtkImageData>>& images, int columns, int gap) {
  if (images.empty()) throw std::invalid_argument("TileImages: no images");
  int dims[3];
  images[0]->GetDimensions(dims);
  const int comps = images[0]->GetNumberOfScalarComponents();
  for (const auto& im : images) {
    int d[3];
    im->GetDimensions(d);
    if (d[0] != dims[0] || d[1] != dims[1] || im->GetNumberOfScalarComponents() != comps ||
        im->GetScalarType() != VTK_UNSIGNED_CHAR)
      throw std::invalid_argument("TileImages: images differ in size, components or type");
  }
  const int n = int(images.size());
  const int cols = columns <= 0 ? n : std::min(columns, n);
  const int rows = (n + cols - 1) / cols;
  const int W = cols * dims[0] + (cols - 1) * gap, H = rows * dims[1] + (rows - 1) * gap;
  auto out = Ptr<vtkImageData>::New();
  out->SetDimensions(W, H, 1);
  out->AllocateScalars(VTK_UNSIGNED_CHAR, comps);
  auto* dst = static_cast<unsigned char*>(out->GetScalarPointer());
  std::memset(dst, 255, size_t(W) * H * comps);  // white gaps
  for (int k = 0; k < n; ++k) {
    // panel k goes left to right, top to bottom; image rows run bottom-up
    const int col = k % cols, row_from_top = k / cols;
    const int x0 = col * (dims[0] + gap), y0 = H - (row_from_top + 1) * dims[1] - row_from_top * gap;
    const auto* src = static_cast<const unsigned char*>(images[k]->GetScalarPointer());
    for (int y = 0; y < dims[1]; ++y)
      std::memcpy(dst + (size_t(y0 + y) * W + x0) * comps, src + size_t(y) * dims[0] * comps, size_t(dims[0]) * comps);
  }
  return out;
}

}  // namespace wobble::pipelines
