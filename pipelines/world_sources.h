// VTK sources that turn a wobble::World into vtkPolyData, in world coordinates (2D bodies at
// z = 0; 3D bodies in 3D). One hierarchy for every body kind: each source is a
// vtkPolyDataAlgorithm with no input over a World and a body index (WorldSourceBase); set the
// world and the body, and call Modified() after the world has changed so that the next
// Update() redraws. A source asked for a body of a kind it cannot draw (or for no world, or a
// body the world does not have) reports it with vtkErrorMacro and outputs nothing.
//
// Per body, for both kinds (FFD bodies of the thesis, Witkin & Welch linear bodies; each a
// BodyPartSource, which dispatches on the body's kind). An FFD body of either dimension is drawn
// by one code over Dim (issue 45: Frame, LocalPosition, PointVelocity and GroundForce of the
// library); points and vectors always have 3 components, z = 0 in 2D.
//   LatticeSource    the control structure, as vertices and grid lines.
//                    FFD: the deformed control lattice, a line along each axis through every
//                    row of control points; point arrays rest_position (body frame) and
//                    displacement (body frame, Σ γ_d d^d_ij of Eq. 4.2: the deformation alone,
//                    without the rigid motion).
//                    Linear: the "control box", a grid of lines over the box the mass points
//                    span (3 lines per direction and face), each cut into Pieces and carried
//                    by x = R p(u), so a quadratic body's bend shows; the grid's nodes as
//                    vertices; point array rest_position (u).
//   MassPointSource  the mass points as vertices; arrays mass and velocity, and for FFD
//                    bodies applied_force (gravity plus the ground's penalty force of
//                    Eq. 4.24/4.25 on the points tied to it: the line or terrain in 2D, the
//                    plane or heightfield in 3D; world frame) and in_contact (1 for a point
//                    tied to the ground)
//   ShapeSource      the body's drawing.
//                    FFD: the drawing polylines of the body's file, resampled finer than the
//                    mass points: each segment is cut into SamplesPerSegment pieces and every
//                    sample is moved by the FFD (the thesis simulates few points and draws
//                    many, §4.10). 2D: point array lattice_coords. 3D adds the object's mesh
//                    as triangles with every vertex moved by the FFD, and the point array
//                    displacement (B γ, body frame) over mesh and polylines.
//                    Linear: a LinearDrawing (SetDrawing: polylines and, in 3D, a triangle
//                    surface) carried by x = R p(u).
//   TrailSource      (2D FFD bodies) trajectories of chosen points (lattice coordinates): call
//                    Record() after each frame; polylines with a point array time
// Of the world (Body is not used):
//   GroundSource     the ground line with its slope, or the terrain's profile, as a filled band of
//                    given length and depth;
//                    with a 3D FFD body, the 3D ground plane: a square of side Length under
//                    the 3D bodies' centre
//   SpringSource     the world's springs (of FFD bodies of either dimension) as lines
//                    anchor → held point; cell array stretch
//   AnchorSource     named points (material points of any body, fixed places) as vertices,
//                    e.g. the control points of a script
// Every output has a TimeValue field array: the world's time.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <tuple>
#include <vector>
#include <vtkPolyDataAlgorithm.h>

#include "wobble/body/linear_shapes.h"
#include "wobble/dynamics/kinematics.h"
#include "wobble/world/world.h"

namespace wobble::pipelines {

// Body b's name, or body<b> when it has none: how the exports name its files and nodes.
std::string BodyLabel(const World& world, int b);

// A point of a 2D or 3D world in VTK's three coordinates (z = 0 in 2D); for fixed sizes
// without a temporary on the heap.
Eigen::Vector3d To3(const Eigen::VectorXd& p);
template <int Dim> Eigen::Vector3d To3(const Eigen::Matrix<double, Dim, 1>& p) {
  if constexpr (Dim == 2) return Eigen::Vector3d(p.x(), p.y(), 0.0);
  else return p;
}

// What every source shares: the world and which body of it.
class WorldSourceBase : public vtkPolyDataAlgorithm {
 public:
  vtkTypeMacro(WorldSourceBase, vtkPolyDataAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;
  // The world is not owned; it must outlive the source's updates.
  void SetWorld(const World* world) {
    world_ = world;
    Modified();
  }
  const World* GetWorld() const { return world_; }
  vtkSetMacro(Body, int);
  vtkGetMacro(Body, int);

 protected:
  WorldSourceBase() { SetNumberOfInputPorts(0); }
  // What a source needs: a world, or also Body as a body of it (of any kind, or of one kind).
  enum class Needs { kWorld, kAnyBody, kFfdBody, kLinearBody };
  // Reports (vtkErrorMacro) and returns false when the world or the body is not what `needs` says.
  bool Check(Needs needs);
  const World* world_ = nullptr;
  int Body = 0;
};

// A part of one body of either kind: RequestData checks the body and draws it with the
// kind's own function (false: nothing drawn, already reported). DrawFfd serves FFD bodies of
// both dimensions: each source's calls its own DrawFfdOf<Dim> with the body's dimension.
class BodyPartSource : public WorldSourceBase {
 public:
  vtkTypeMacro(BodyPartSource, WorldSourceBase);

 protected:
  BodyPartSource() = default;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) final;
  virtual bool DrawFfd(vtkPolyData* out) = 0;
  virtual bool DrawLinear(vtkPolyData* out) = 0;
};

class LatticeSource : public BodyPartSource {
 public:
  static LatticeSource* New();
  vtkTypeMacro(LatticeSource, BodyPartSource);
  // Linear bodies: pieces each grid line is cut into (>= 1).
  vtkSetClampMacro(Pieces, int, 1, 10000);
  vtkGetMacro(Pieces, int);

 protected:
  LatticeSource() = default;
  bool DrawFfd(vtkPolyData* out) override;
  bool DrawLinear(vtkPolyData* out) override;
  int Pieces = 12;

 private:
  template <int Dim> bool DrawFfdOf(vtkPolyData* out);
};

class MassPointSource : public BodyPartSource {
 public:
  static MassPointSource* New();
  vtkTypeMacro(MassPointSource, BodyPartSource);

 protected:
  MassPointSource() = default;
  bool DrawFfd(vtkPolyData* out) override;
  bool DrawLinear(vtkPolyData* out) override;

 private:
  template <int Dim> bool DrawFfdOf(vtkPolyData* out);
};

// ShapeSource's drawing polylines of an FFD body of Dim, resampled: every sample's lattice
// coordinates and its b0 and B (BodyModelN::LocalBasis), made once per body and sample
// count: the lattice weights of a sample never change, only q does.
template <int Dim> struct DrawingSamples {
  const BodyModelN<Dim>* body = nullptr;
  int per_segment = -1;
  std::vector<Eigen::Matrix<double, Dim, 1>> st, b0;
  std::vector<MatND<double, Dim>> B;
  std::vector<std::pair<int, bool>> polylines;  // samples per polyline, closed
};
// The drawing of `body` resampled per_segment times per segment (a closed polyline's last
// segment returns to its first point, which is not repeated; an open one ends on its last
// point): what ShapeSource draws, and the glTF export (gltf_export.h) writes.
template <int Dim> DrawingSamples<Dim> MakeDrawingSamples(const BodyModelN<Dim>& body, int per_segment);

class ShapeSource : public BodyPartSource {
 public:
  static ShapeSource* New();
  vtkTypeMacro(ShapeSource, BodyPartSource);
  void PrintSelf(ostream& os, vtkIndent indent) override;
  // FFD bodies: pieces each drawing segment is cut into (>= 1).
  vtkSetClampMacro(SamplesPerSegment, int, 1, 100000);
  vtkGetMacro(SamplesPerSegment, int);
  // 2D FFD bodies: lattice coordinates of every sample, in output order (one polyline after
  // the other), as of the last update.
  std::vector<Eigen::Vector2d> SampleLatticeCoords() const;

  // Which part of the drawing: lines (polylines), surface (triangles: a linear body's drawing,
  // a 3D FFD body's mesh) or both (default).
  vtkSetMacro(Lines, bool);
  vtkSetMacro(Surface, bool);
  // Linear bodies: the drawing (in the body's undeformed coordinates).
  void SetDrawing(const LinearDrawing& drawing) {
    drawing_ = drawing;
    Modified();
  }
  // FFD bodies: the closed polylines of the drawing as polygons (the clean style's fill)
  // instead of every polyline as lines.
  vtkSetMacro(FillClosed, bool);

 protected:
  ShapeSource() = default;
  bool DrawFfd(vtkPolyData* out) override;
  bool DrawLinear(vtkPolyData* out) override;
  int SamplesPerSegment = 16;
  LinearDrawing drawing_;
  bool Lines = true, Surface = true, FillClosed = false;

 private:
  template <int Dim> const DrawingSamples<Dim>& SamplesOf(const BodyModelN<Dim>& body);  // made if stale
  template <int Dim> bool DrawFfdOf(vtkPolyData* out);
  std::tuple<DrawingSamples<2>, DrawingSamples<3>> samples_;  // by Dim - 2
};

class GroundSource : public WorldSourceBase {
 public:
  static GroundSource* New();
  vtkTypeMacro(GroundSource, WorldSourceBase);
  void PrintSelf(ostream& os, vtkIndent indent) override;
  // The band is centred on the ground point nearest Center, Length along the ground and
  // Depth below it.
  vtkSetVector2Macro(Center, double);
  vtkGetVector2Macro(Center, double);
  vtkSetMacro(Length, double);
  vtkGetMacro(Length, double);
  vtkSetMacro(Depth, double);
  vtkGetMacro(Depth, double);

 protected:
  GroundSource() = default;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int DrawTerrain(const Terrain& terrain, vtkPoints* points, vtkPolyData* out);
  int DrawHeightfield(const Heightfield& field, vtkPoints* points, vtkPolyData* out);
  double Center[2] = {0, 0};
  double Length = 2000.0, Depth = 100.0;
};

// Sets `ground` to draw the whole terrain once: its profile and as much again either side,
// filled to half its width below its lowest point (the .vtp series' and the .glb's terrain).
void FrameWholeTerrain(const Terrain& terrain, GroundSource* ground);

class SpringSource : public WorldSourceBase {
 public:
  static SpringSource* New();
  vtkTypeMacro(SpringSource, WorldSourceBase);

 protected:
  SpringSource() = default;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
};

class TrailSource : public WorldSourceBase {
 public:
  static TrailSource* New();
  vtkTypeMacro(TrailSource, WorldSourceBase);
  // The points to follow, by lattice coordinates (s, t) of the FFD body Body; clears the history.
  void SetTrackedPoints(const std::vector<Eigen::Vector2d>& lattice_coords);
  // Appends the tracked points' current world positions at the world's time.
  void Record();
  void ClearHistory();
  int GetNumberOfSamples() const { return int(times_.size()); }

 protected:
  TrailSource() = default;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

 private:
  std::vector<Eigen::Vector2d> tracked_;
  std::vector<double> times_;
  std::vector<std::vector<Eigen::Vector2d>> history_;  // [sample][tracked point]
};

class AnchorSource : public WorldSourceBase {
 public:
  static AnchorSource* New();
  vtkTypeMacro(AnchorSource, WorldSourceBase);
  struct Anchor {
    std::string name;
    MaterialPoint point;    // body < 0: a fixed place
    Eigen::VectorXd place;  // the fixed place
  };
  void SetAnchors(std::vector<Anchor> anchors) {
    anchors_ = std::move(anchors);
    Modified();
  }

 protected:
  AnchorSource() = default;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  std::vector<Anchor> anchors_;
};

// The world position x = t + R (b0 + B γ) (Eq. 4.2) of a point of FFD body `body` of Dim with
// rest position b0 and mode matrix B, at the world's current state.
template <int Dim, class Derived>
Eigen::Matrix<double, Dim, 1> WorldPosition(const World& world, int body, const Eigen::Matrix<double, Dim, 1>& b0,
                                            const Eigen::MatrixBase<Derived>& B) {
  const VecQ<double>& q = world.q(body);
  return WorldFromLocal(Frame<Dim, double>(q), LocalPosition<double>(b0, B, q));
}

// World position of lattice coordinates st of FFD body `body` (of st's dimension) at the
// world's current state (through BodyModelN::LocalBasis).
template <int Dim>
Eigen::Matrix<double, Dim, 1> WorldPositionOf(const World& world, int body, const Eigen::Matrix<double, Dim, 1>& st);

// A box holding the deformed control points of FFD body `body` of Dim, so every point of the
// body (by the convex hull).
template <int Dim> Eigen::AlignedBox<double, Dim> BodyBounds(const World& world, int body);
// The same for an FFD body of either dimension, in 3 coordinates (z = 0 in 2D).
Eigen::AlignedBox3d FfdBodyBounds(const World& world, int body);

// The ground a body stands on, as drawn: 2 for the 2D ground (line or terrain), 3 for the 3D
// plane, 0 for none. FFD bodies always stand on theirs; a linear body only when it touches it
// (World::ground_contact), else the ground is not drawn for it (Witkin & Welch's scenes).
int GroundDimensionOf(const World& world, int body);

// World position of undeformed point u of linear body `body` (x = R p(u)) as 3 numbers (z = 0 in 2D).
Eigen::Vector3d LinearWorldPoint(const World& world, int body, const Eigen::VectorXd& u);

// A box holding every point of a linear body now: its mass points and the corners of its
// drawing's sampled points (a quadratic deformation can bulge beyond the mass points' hull, so
// the drawing's own samples are included when given).
Eigen::AlignedBox3d LinearBodyBounds(const World& world, int body, const LinearDrawing* drawing = nullptr);

}  // namespace wobble::pipelines
