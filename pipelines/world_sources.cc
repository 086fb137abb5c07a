#include "pipelines/world_sources.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkDoubleArray.h>
#include <vtkFieldData.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkObjectFactory.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkUnsignedCharArray.h>

#include "wobble/dynamics/forces.h"
#include "wobble/dynamics/kinematics.h"

namespace wobble::pipelines {
namespace {

template <class T> using Ptr = vtkSmartPointer<T>;

vtkPolyData* OutputOf(vtkInformationVector* out) {
  return vtkPolyData::SafeDownCast(out->GetInformationObject(0)->Get(vtkDataObject::DATA_OBJECT()));
}

Ptr<vtkDoubleArray> Vectors(const char* name, vtkIdType n) {
  auto a = Ptr<vtkDoubleArray>::New();
  a->SetName(name);
  a->SetNumberOfComponents(3);
  a->SetNumberOfTuples(n);
  return a;
}

Ptr<vtkDoubleArray> Scalars(const char* name, vtkIdType n) {
  auto a = Ptr<vtkDoubleArray>::New();
  a->SetName(name);
  a->SetNumberOfTuples(n);
  return a;
}

Ptr<vtkPoints> DoublePoints() {
  auto points = Ptr<vtkPoints>::New();
  points->SetDataTypeToDouble();
  return points;
}

// Every output carries the world's time as field data (ParaView reads TimeValue).
void AddTimeValue(vtkPolyData* out, double time) {
  auto t = Ptr<vtkDoubleArray>::New();
  t->SetName("TimeValue");
  t->InsertNextValue(time);
  out->GetFieldData()->AddArray(t);
}

// The box a linear body's mass points span in undeformed coordinates.
void UndeformedBox(const LinearBodyModel& model, Eigen::VectorXd* lo, Eigen::VectorXd* hi) {
  *lo = model.def().points[0];
  *hi = *lo;
  for (const Eigen::VectorXd& u : model.def().points) {
    *lo = lo->cwiseMin(u);
    *hi = hi->cwiseMax(u);
  }
}

}  // namespace

std::string BodyLabel(const World& world, int b) {
  return world.body_name(b).empty() ? "body" + std::to_string(b) : world.body_name(b);
}

Eigen::Vector3d To3(const Eigen::VectorXd& x) { return Eigen::Vector3d(x[0], x[1], x.size() > 2 ? x[2] : 0.0); }

template <int Dim>
Eigen::Matrix<double, Dim, 1> WorldPositionOf(const World& world, int body, const Eigen::Matrix<double, Dim, 1>& st) {
  Eigen::Matrix<double, Dim, 1> b0;
  MatND<double, Dim> B;
  world.body<Dim>(body).LocalBasis(st, &b0, &B);
  return WorldPosition(world, body, b0, B);
}
template Eigen::Vector2d WorldPositionOf<2>(const World&, int, const Eigen::Vector2d&);
template Eigen::Vector3d WorldPositionOf<3>(const World&, int, const Eigen::Vector3d&);

template <int Dim> Eigen::AlignedBox<double, Dim> BodyBounds(const World& world, int body) {
  const BodyModelN<Dim>& m = world.body<Dim>(body);
  const VecQ<double>& q = world.q(body);
  const Frame<Dim, double> frame(q);
  const double* gamma = q.data() + Group<Dim>::kRigidParams;
  Eigen::AlignedBox<double, Dim> box;
  for (int c = 0; c < m.lattice().size(); ++c) {
    Eigen::Matrix<double, Dim, 1> l = m.rest_control()[size_t(c)];
    for (int d = 0; d < m.num_modes(); ++d) l += m.modes()[size_t(d)].displacement[size_t(c)] * gamma[d];
    box.extend(WorldFromLocal(frame, l));
  }
  return box;
}
template Eigen::AlignedBox2d BodyBounds<2>(const World&, int);
template Eigen::AlignedBox3d BodyBounds<3>(const World&, int);

Eigen::AlignedBox3d FfdBodyBounds(const World& world, int body) {
  if (world.dim(body) == 3) return BodyBounds<3>(world, body);
  const Eigen::AlignedBox2d flat = BodyBounds<2>(world, body);
  return Eigen::AlignedBox3d(To3(flat.min()), To3(flat.max()));
}

Eigen::Vector3d LinearWorldPoint(const World& world, int body, const Eigen::VectorXd& u) {
  const LinearBodyModel& model = world.linear_model(body);
  return To3(world.linear_R(body) * model.Basis(u));
}

Eigen::AlignedBox3d LinearBodyBounds(const World& world, int body, const LinearDrawing* drawing) {
  const LinearBodyModel& model = world.linear_model(body);
  Eigen::AlignedBox3d box;
  for (const Eigen::VectorXd& u : model.def().points) box.extend(LinearWorldPoint(world, body, u));
  if (drawing) {
    for (const auto& line : drawing->polylines)
      for (const Eigen::VectorXd& u : line.points) box.extend(LinearWorldPoint(world, body, u));
    for (const Eigen::VectorXd& u : drawing->vertices) box.extend(LinearWorldPoint(world, body, u));
  }
  return box;
}

void WorldSourceBase::PrintSelf(ostream& os, vtkIndent indent) {
  Superclass::PrintSelf(os, indent);
  os << indent << "World: " << world_ << "\n" << indent << "Body: " << Body << "\n";
}

bool WorldSourceBase::Check(Needs needs) {
  if (!world_) {
    vtkErrorMacro("no world set");
    return false;
  }
  if (needs == Needs::kWorld) return true;
  if (Body < 0 || Body >= world_->num_bodies()) {
    vtkErrorMacro("body " << Body << " not in the world (" << world_->num_bodies() << " bodies)");
    return false;
  }
  const BodyKind kind = world_->kind(Body);
  if (needs == Needs::kFfdBody && !world_->IsFfd(Body, 2)) {
    vtkErrorMacro("body " << Body << " is not an FFD body of the world");
    return false;
  }
  if (needs == Needs::kLinearBody && kind != BodyKind::kLinear) {
    vtkErrorMacro("body " << Body << " is not a linear body of the world");
    return false;
  }
  return true;
}

int BodyPartSource::RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector* out_vec) {
  if (!Check(Needs::kAnyBody)) return 0;
  vtkPolyData* out = OutputOf(out_vec);
  const BodyKind kind = world_->kind(Body);
  const bool drawn = kind == BodyKind::kLinear ? DrawLinear(out) : DrawFfd(out);
  if (!drawn) return 0;
  AddTimeValue(out, world_->time());
  return 1;
}

// ---------------------------------------------------------------------------------------
vtkStandardNewMacro(LatticeSource);

bool LatticeSource::DrawFfd(vtkPolyData* out) { return world_->dim(Body) == 3 ? DrawFfdOf<3>(out) : DrawFfdOf<2>(out); }

template <int Dim> bool LatticeSource::DrawFfdOf(vtkPolyData* out) {
  using Point = Eigen::Matrix<double, Dim, 1>;
  const BodyModelN<Dim>& body = world_->body<Dim>(Body);
  const VecQ<double>& q = world_->q(Body);
  const double* gamma = q.data() + Group<Dim>::kRigidParams;
  const LatticeN<Dim>& lat = body.lattice();
  const Frame<Dim, double> frame(q);
  const int n = lat.size();

  // deformed control points: L_ij + Σ γ_d d^d_ij (Eq. 4.2), then into the world
  auto points = DoublePoints();
  points->SetNumberOfPoints(n);
  auto rest = Vectors("rest_position", n);
  auto disp = Vectors("displacement", n);
  for (int c = 0; c < n; ++c) {
    Point d = Point::Zero();
    for (int m = 0; m < body.num_modes(); ++m) d += body.modes()[size_t(m)].displacement[size_t(c)] * gamma[m];
    const Point& r = body.rest_control()[size_t(c)];
    points->SetPoint(c, To3(WorldFromLocal(frame, Point(r + d))).data());
    rest->SetTuple(c, To3(r).data());
    disp->SetTuple(c, To3(d).data());
  }

  // a vertex per control point, and a line along each axis through every row of control points
  // (the last axis first: in 2D a line per lattice row, then per column)
  auto verts = Ptr<vtkCellArray>::New();
  for (vtkIdType c = 0; c < n; ++c) verts->InsertNextCell(1, &c);
  auto lines = Ptr<vtkCellArray>::New();
  const typename LatticeN<Dim>::Sizes size = lat.sizes();
  for (int axis = Dim - 1; axis >= 0; --axis)
    for (int c = 0; c < n; ++c) {
      typename LatticeN<Dim>::Cell cell = lat.CellOf(c);
      if (cell[size_t(axis)] != 0) continue;  // a row starts at its first control point
      lines->InsertNextCell(size[size_t(axis)]);
      for (int k = 0; k < size[size_t(axis)]; ++k) {
        cell[size_t(axis)] = k;
        lines->InsertCellPoint(lat.FlatIndex(cell));
      }
    }
  out->SetPoints(points);
  out->SetVerts(verts);
  out->SetLines(lines);
  out->GetPointData()->AddArray(rest);
  out->GetPointData()->AddArray(disp);
  return true;
}

bool LatticeSource::DrawLinear(vtkPolyData* out) {
  const LinearBodyModel& model = world_->linear_model(Body);
  const int d = model.dim();
  Eigen::VectorXd lo, hi;
  UndeformedBox(model, &lo, &hi);
  auto level = [&](int axis, int k) { return lo[axis] + 0.5 * k * (hi[axis] - lo[axis]); };  // k = 0, 1, 2

  auto points = DoublePoints();
  auto rest = Ptr<vtkDoubleArray>::New();
  rest->SetName("rest_position");
  rest->SetNumberOfComponents(3);
  auto add = [&](const Eigen::VectorXd& u) {
    const Eigen::Vector3d x = LinearWorldPoint(*world_, Body, u);
    const Eigen::Vector3d r = To3(u);
    rest->InsertNextTuple3(r.x(), r.y(), r.z());
    return points->InsertNextPoint(x.x(), x.y(), x.z());
  };
  // the 3^d grid nodes as vertices
  auto verts = Ptr<vtkCellArray>::New();
  const int nodes = d == 2 ? 9 : 27;
  for (int i = 0; i < nodes; ++i) {
    Eigen::VectorXd u(d);
    for (int a = 0, rest_i = i; a < d; ++a, rest_i /= 3) u[a] = level(a, rest_i % 3);
    const vtkIdType id = add(u);
    verts->InsertNextCell(1, &id);
  }
  // lines along every axis through the other axes' three levels, cut into Pieces
  auto lines = Ptr<vtkCellArray>::New();
  const int others = d == 2 ? 3 : 9;
  for (int axis = 0; axis < d; ++axis)
    for (int o = 0; o < others; ++o) {
      Eigen::VectorXd u(d);
      for (int a = 0, rest_o = o; a < d; ++a) {
        if (a == axis) continue;
        u[a] = level(a, rest_o % 3);
        rest_o /= 3;
      }
      lines->InsertNextCell(Pieces + 1);
      for (int p = 0; p <= Pieces; ++p) {
        u[axis] = lo[axis] + (hi[axis] - lo[axis]) * double(p) / Pieces;
        lines->InsertCellPoint(add(u));
      }
    }
  out->SetPoints(points);
  out->SetVerts(verts);
  out->SetLines(lines);
  out->GetPointData()->AddArray(rest);
  return true;
}

// ---------------------------------------------------------------------------------------
vtkStandardNewMacro(MassPointSource);

bool MassPointSource::DrawFfd(vtkPolyData* out) { return world_->dim(Body) == 3 ? DrawFfdOf<3>(out) : DrawFfdOf<2>(out); }

template <int Dim> bool MassPointSource::DrawFfdOf(vtkPolyData* out) {
  using Point = Eigen::Matrix<double, Dim, 1>;
  const BodyModelN<Dim>& body = world_->body<Dim>(Body);
  const BodyState<Dim, double>& s = world_->state<Dim>(Body);
  const Frame<Dim, double> frame(s.q);
  const int n = body.num_points();
  const Point gravity = world_->options().params.gravity_on ? GravityFor<Dim>(world_->options().params) : Point::Zero();

  auto points = DoublePoints();
  points->SetNumberOfPoints(n);
  auto mass = Scalars("mass", n);
  auto velocity = Vectors("velocity", n);
  auto force = Vectors("applied_force", n);
  auto contact = Ptr<vtkUnsignedCharArray>::New();
  contact->SetName("in_contact");
  contact->SetNumberOfTuples(n);
  contact->FillValue(0);
  std::vector<Point> x(static_cast<size_t>(n)), v(x), f(x);
  for (int k = 0; k < n; ++k) {
    const auto B = body.mode_matrix(k);
    const Point l = LocalPosition<double>(body.rest_local(k), B, s.q);
    x[size_t(k)] = WorldFromLocal(frame, l);
    v[size_t(k)] = PointVelocity(frame, s.qd, l, B);
    f[size_t(k)] = body.mass(k) * gravity;
  }
  // the ground's penalty and capped friction on every point tied to it (Eq. 4.24, 4.25), as
  // the step's forces see them (ContactSet::kFrozen: the state's contacts)
  ForEachPointInContact(body, GroundFor<Dim>(world_->options().params), s, frame,
                        [&](int k, const Point&, const Point& xk, const Point& vk, const Point& anchor, const auto& face, int) {
                          bool slipping;
                          f[size_t(k)] += GroundForce(face, xk, vk, anchor, &slipping);
                          contact->SetValue(k, 1);
                        },
                        ContactSet::kFrozen);
  auto verts = Ptr<vtkCellArray>::New();
  for (vtkIdType k = 0; k < n; ++k) {
    points->SetPoint(k, To3(x[size_t(k)]).data());
    mass->SetValue(k, body.mass(int(k)));
    velocity->SetTuple(k, To3(v[size_t(k)]).data());
    force->SetTuple(k, To3(f[size_t(k)]).data());
    verts->InsertNextCell(1, &k);
  }
  out->SetPoints(points);
  out->SetVerts(verts);
  for (vtkDataArray* a : {static_cast<vtkDataArray*>(mass), static_cast<vtkDataArray*>(velocity),
                          static_cast<vtkDataArray*>(force), static_cast<vtkDataArray*>(contact)})
    out->GetPointData()->AddArray(a);
  return true;
}

bool MassPointSource::DrawLinear(vtkPolyData* out) {
  const LinearBodyModel& model = world_->linear_model(Body);
  const Eigen::MatrixXd& R = world_->linear_R(Body);
  const Eigen::MatrixXd& R_dot = world_->linear_R_dot(Body);
  const int n = model.num_points();
  auto points = DoublePoints();
  points->SetNumberOfPoints(n);
  auto mass = Scalars("mass", n);
  auto velocity = Vectors("velocity", n);
  auto verts = Ptr<vtkCellArray>::New();
  for (vtkIdType k = 0; k < n; ++k) {
    const Eigen::VectorXd p = model.Basis(model.def().points[k]);
    const Eigen::Vector3d x = To3(R * p), v = To3(R_dot * p);  // x = R p, ẋ = Ṙ p (§2.2)
    points->SetPoint(k, x.x(), x.y(), x.z());
    velocity->SetTuple3(k, v.x(), v.y(), v.z());
    mass->SetValue(k, model.def().masses[k]);
    verts->InsertNextCell(1, &k);
  }
  out->SetPoints(points);
  out->SetVerts(verts);
  out->GetPointData()->AddArray(mass);
  out->GetPointData()->AddArray(velocity);
  return true;
}

// ---------------------------------------------------------------------------------------
vtkStandardNewMacro(ShapeSource);

void ShapeSource::PrintSelf(ostream& os, vtkIndent indent) {
  Superclass::PrintSelf(os, indent);
  os << indent << "SamplesPerSegment: " << SamplesPerSegment << "\n";
}

template <int Dim> DrawingSamples<Dim> MakeDrawingSamples(const BodyModelN<Dim>& body, int per_segment) {
  using Point = Eigen::Matrix<double, Dim, 1>;
  DrawingSamples<Dim> samples;
  const LatticeN<Dim>& lat = body.lattice();
  for (const PolylineN<Dim>& pl : body.def().shapes) {
    const int np = int(pl.points.size());
    if (np < 2) continue;  // nothing to draw
    // a closed polyline's last segment returns to its first point, which is not repeated
    const int segments = pl.closed ? np : np - 1;
    for (int seg = 0; seg < segments; ++seg) {
      const Point a = pl.points[size_t(seg)], b = pl.points[size_t((seg + 1) % np)];
      for (int k = 0; k < per_segment; ++k)
        samples.st.push_back(lat.LocalCoords(a + (b - a) * (double(k) / per_segment)));
    }
    if (!pl.closed) samples.st.push_back(lat.LocalCoords(pl.points.back()));
    samples.polylines.push_back({segments * per_segment + (pl.closed ? 0 : 1), pl.closed});
  }
  for (const Point& st : samples.st) {
    Point b0;
    MatND<double, Dim> B;
    body.LocalBasis(st, &b0, &B);
    samples.b0.push_back(b0);
    samples.B.push_back(B);
  }
  samples.body = &body;
  samples.per_segment = per_segment;
  return samples;
}
template DrawingSamples<2> MakeDrawingSamples<2>(const BodyModelN<2>&, int);
template DrawingSamples<3> MakeDrawingSamples<3>(const BodyModelN<3>&, int);

template <int Dim> const DrawingSamples<Dim>& ShapeSource::SamplesOf(const BodyModelN<Dim>& body) {
  DrawingSamples<Dim>& samples = std::get<Dim - 2>(samples_);
  if (samples.body != &body || samples.per_segment != SamplesPerSegment) samples = MakeDrawingSamples(body, SamplesPerSegment);
  return samples;
}

std::vector<Eigen::Vector2d> ShapeSource::SampleLatticeCoords() const { return std::get<0>(samples_).st; }

bool ShapeSource::DrawFfd(vtkPolyData* out) { return world_->dim(Body) == 3 ? DrawFfdOf<3>(out) : DrawFfdOf<2>(out); }

template <int Dim> bool ShapeSource::DrawFfdOf(vtkPolyData* out) {
  using Point = Eigen::Matrix<double, Dim, 1>;
  const BodyModelN<Dim>& body = world_->body<Dim>(Body);
  const LatticeN<Dim>& lat = body.lattice();
  const VecQ<double>& q = world_->q(Body);
  const Frame<Dim, double> frame(q);
  auto points = DoublePoints();
  // what a point carries besides its place: in 2D its lattice coordinates (the interactive view
  // picks them), in 3D its displacement B γ (body frame), the deformation alone
  auto carried = Ptr<vtkDoubleArray>::New();
  carried->SetName(Dim == 2 ? "lattice_coords" : "displacement");
  carried->SetNumberOfComponents(Dim == 2 ? 2 : 3);
  auto add = [&](const Point& st, const Point& b0, const auto& B) {
    if constexpr (Dim == 2) carried->InsertNextTuple(st.data());
    else carried->InsertNextTuple(Point(LocalPosition<double>(Point(Point::Zero()), B, q)).data());
    return points->InsertNextPoint(To3(WorldFromLocal(frame, LocalPosition<double>(b0, B, q))).data());
  };
  // the mesh (a 3D body's): its vertices' bases were made once, with the body (mesh_rest_local)
  const TriangleMeshN<Dim>& mesh = body.def().mesh;
  auto polys = Ptr<vtkCellArray>::New();
  if (Surface && !mesh.empty()) {
    const vtkIdType base = points->GetNumberOfPoints();
    for (int v = 0; v < int(mesh.points.size()); ++v)
      add(lat.LocalCoords(mesh.points[size_t(v)]), body.mesh_rest_local(v), body.mesh_mode_matrix(v));
    for (const std::array<int, 3>& t : mesh.triangles) {
      const vtkIdType ids[3] = {base + t[0], base + t[1], base + t[2]};
      polys->InsertNextCell(3, ids);
    }
  }
  // the polylines, resampled: as lines, or the closed ones as polygons (FillClosed)
  auto lines = Ptr<vtkCellArray>::New();
  const DrawingSamples<Dim>& samples = SamplesOf(body);
  if (Lines) {
    vtkIdType first = points->GetNumberOfPoints();
    for (size_t k = 0; k < samples.st.size(); ++k) add(samples.st[k], samples.b0[k], samples.B[k]);
    for (const auto& [count, closed] : samples.polylines) {
      if (FillClosed && closed) {
        polys->InsertNextCell(count);
        for (int k = 0; k < count; ++k) polys->InsertCellPoint(first + k);
      } else if (!FillClosed) {
        lines->InsertNextCell(count + (closed ? 1 : 0));
        for (int k = 0; k < count; ++k) lines->InsertCellPoint(first + k);
        if (closed) lines->InsertCellPoint(first);
      }
      first += count;
    }
  }
  out->SetPoints(points);
  out->SetPolys(polys);
  out->SetLines(lines);
  out->GetPointData()->AddArray(carried);
  return true;
}

bool ShapeSource::DrawLinear(vtkPolyData* out) {
  const int d = world_->linear_model(Body).dim();
  if (drawing_.dim() != 0 && drawing_.dim() != d) {
    vtkErrorMacro("the drawing is " << drawing_.dim() << "D, the body " << d << "D");
    return false;
  }
  auto points = DoublePoints();
  auto add = [&](const Eigen::VectorXd& u) {
    const Eigen::Vector3d x = LinearWorldPoint(*world_, Body, u);
    return points->InsertNextPoint(x.x(), x.y(), x.z());
  };
  auto lines = Ptr<vtkCellArray>::New();
  if (Lines)
    for (const LinearDrawing::Polyline& line : drawing_.polylines) {
      const vtkIdType first = points->GetNumberOfPoints();
      lines->InsertNextCell(vtkIdType(line.points.size()) + (line.closed ? 1 : 0));
      for (const Eigen::VectorXd& u : line.points) lines->InsertCellPoint(add(u));
      if (line.closed) lines->InsertCellPoint(first);
    }
  auto polys = Ptr<vtkCellArray>::New();
  if (Surface && !drawing_.triangles.empty()) {
    const vtkIdType base = points->GetNumberOfPoints();
    for (const Eigen::VectorXd& u : drawing_.vertices) add(u);
    for (const auto& t : drawing_.triangles) {
      const vtkIdType ids[3] = {base + t[0], base + t[1], base + t[2]};
      polys->InsertNextCell(3, ids);
    }
  }
  out->SetPoints(points);
  out->SetLines(lines);
  out->SetPolys(polys);
  return true;
}

// ---------------------------------------------------------------------------------------
vtkStandardNewMacro(GroundSource);

void GroundSource::PrintSelf(ostream& os, vtkIndent indent) {
  Superclass::PrintSelf(os, indent);
  os << indent << "Center: " << Center[0] << " " << Center[1] << "\n"
     << indent << "Length: " << Length << "\n" << indent << "Depth: " << Depth << "\n";
}

// A terrain over [Center.x ± Length/2]: its surface as one polyline, and below it one
// trapezoid per non-vertical segment down to Depth under the lowest surface point (convex
// cells: VTK fans polygons, so a whole non-convex profile would fill wrongly).
void FrameWholeTerrain(const Terrain& terrain, GroundSource* ground) {
  const double x0 = terrain.vertices().front().x(), x1 = terrain.vertices().back().x();
  double lo = terrain.vertices().front().y(), hi = lo;
  for (const Eigen::Vector2d& v : terrain.vertices()) lo = std::min(lo, v.y()), hi = std::max(hi, v.y());
  const double span = std::max({x1 - x0, hi - lo, 1.0});
  ground->SetCenter(0.5 * (x0 + x1), lo);
  ground->SetLength(3.0 * span);
  ground->SetDepth(0.5 * span);
}

int GroundSource::DrawTerrain(const Terrain& terrain, vtkPoints* points, vtkPolyData* out) {
  const double x0 = Center[0] - 0.5 * Length, x1 = Center[0] + 0.5 * Length;
  std::vector<Eigen::Vector2d> surface = {{x0, terrain.HeightAt(x0)}};
  for (const Eigen::Vector2d& v : terrain.vertices())
    if (v.x() > x0 && v.x() < x1) surface.push_back(v);
  surface.push_back({x1, terrain.HeightAt(x1)});
  double lowest = surface.front().y();
  for (const Eigen::Vector2d& p : surface) lowest = std::min(lowest, p.y());
  const double bottom = lowest - Depth;
  const vtkIdType n = vtkIdType(surface.size());
  auto height = Scalars("height", 2 * int(n));  // signed height above the surface
  for (vtkIdType k = 0; k < n; ++k) {
    points->InsertNextPoint(surface[k].x(), surface[k].y(), 0.0);
    height->SetValue(k, 0.0);
  }
  for (vtkIdType k = 0; k < n; ++k) {
    points->InsertNextPoint(surface[k].x(), bottom, 0.0);
    height->SetValue(n + k, bottom - terrain.HeightAt(surface[k].x()));
  }
  auto polys = Ptr<vtkCellArray>::New();
  for (vtkIdType k = 0; k + 1 < n; ++k) {
    if (surface[k].x() == surface[k + 1].x()) continue;  // a cliff face: the neighbours fill it
    const vtkIdType quad[4] = {k, k + 1, n + k + 1, n + k};
    polys->InsertNextCell(4, quad);
  }
  auto lines = Ptr<vtkCellArray>::New();
  lines->InsertNextCell(n);
  for (vtkIdType k = 0; k < n; ++k) lines->InsertCellPoint(k);
  out->SetPoints(points);
  out->SetPolys(polys);
  out->SetLines(lines);
  out->GetPointData()->AddArray(height);
  return 1;
}

int GroundDimensionOf(const World& world, int body) {
  switch (world.kind(body)) {
    case BodyKind::kFfd: return world.dim(body);
    case BodyKind::kLinear: return world.ground_contact(body) ? world.dim(body) : 0;
  }
  return 0;
}

// The grid's triangles as the dynamics splits its cells (heightfield.h), with a "height"
// point array (y) to colour by.
int GroundSource::DrawHeightfield(const Heightfield& field, vtkPoints* points, vtkPolyData* out) {
  const int nx = field.nx(), nz = field.nz();
  auto height = Scalars("height", nx * nz);
  for (int j = 0; j < nz; ++j)
    for (int i = 0; i < nx; ++i) {
      const double y = field.Node(i, j);
      points->InsertNextPoint(field.origin().x() + i * field.spacing().x(), y, field.origin().y() + j * field.spacing().y());
      height->SetValue(i + nx * j, y);
    }
  auto polys = Ptr<vtkCellArray>::New();
  for (int j = 0; j + 1 < nz; ++j)
    for (int i = 0; i + 1 < nx; ++i) {
      const vtkIdType p00 = i + nx * j, p10 = p00 + 1, p01 = p00 + nx, p11 = p01 + 1;
      // counter-clockwise seen from above (+y), so the normals point up
      const vtkIdType lower[3] = {p00, p11, p10}, upper[3] = {p00, p01, p11};
      polys->InsertNextCell(3, lower);
      polys->InsertNextCell(3, upper);
    }
  out->SetPoints(points);
  out->SetPolys(polys);
  out->GetPointData()->AddArray(height);
  return 1;
}

int GroundSource::RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector* out_vec) {
  if (!Check(Needs::kWorld)) return 0;
  vtkPolyData* out = OutputOf(out_vec);
  const Ground& g = world_->options().params.ground;
  auto points = DoublePoints();
  AddTimeValue(out, world_->time());
  // a world of 3D bodies stands on the 3D ground plane
  Eigen::AlignedBox3d on_plane;
  for (int b = 0; b < world_->num_bodies(); ++b) {
    if (GroundDimensionOf(*world_, b) != 3) continue;
    on_plane.extend(world_->kind(b) == BodyKind::kFfd ? FfdBodyBounds(*world_, b) : LinearBodyBounds(*world_, b));
  }
  if (!on_plane.isEmpty()) {
    const GroundPlane& plane = world_->options().params.ground_plane;
    out->SetPoints(points);
    if (!plane.enabled) return 1;
    if (plane.heightfield) return DrawHeightfield(*plane.heightfield, points, out);
    const Eigen::Vector3d n = plane.normal.normalized();
    const Eigen::Vector3d u = n.unitOrthogonal(), v = n.cross(u);
    const Eigen::Vector3d foot = on_plane.center() - n * plane.Height(Eigen::Vector3d(on_plane.center()));
    const double half = 0.5 * Length;
    const double corners[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
    for (const auto& c : corners) points->InsertNextPoint(Eigen::Vector3d(foot + half * (c[0] * u + c[1] * v)).data());
    auto polys = Ptr<vtkCellArray>::New();
    const vtkIdType quad[4] = {0, 1, 2, 3};
    polys->InsertNextCell(4, quad);
    out->SetPolys(polys);
    return 1;
  }
  if (!g.enabled) {
    out->SetPoints(points);
    return 1;
  }
  if (g.terrain) return DrawTerrain(*g.terrain, points, out);
  // the surface segment around the ground point nearest Center, and a band below it
  const Eigen::Vector2d tau = g.tangent(), n = g.normal();
  const Eigen::Vector2d c(Center[0], Center[1]);
  const Eigen::Vector2d foot = g.point + tau * tau.dot(c - g.point);
  const Eigen::Vector2d a = foot - 0.5 * Length * tau, b = foot + 0.5 * Length * tau;
  const Eigen::Vector2d corners[4] = {a, b, b - Depth * n, a - Depth * n};
  for (const Eigen::Vector2d& p : corners) points->InsertNextPoint(p.x(), p.y(), 0.0);
  auto polys = Ptr<vtkCellArray>::New();
  const vtkIdType quad[4] = {0, 1, 2, 3};
  polys->InsertNextCell(4, quad);
  auto lines = Ptr<vtkCellArray>::New();
  const vtkIdType surface[2] = {0, 1};
  lines->InsertNextCell(2, surface);
  auto height = Scalars("height", 4);  // signed height above the ground surface
  for (int k = 0; k < 4; ++k) height->SetValue(k, k < 2 ? 0.0 : -Depth);
  out->SetPoints(points);
  out->SetPolys(polys);
  out->SetLines(lines);
  out->GetPointData()->AddArray(height);
  return 1;
}

// ---------------------------------------------------------------------------------------
vtkStandardNewMacro(SpringSource);

namespace {

// The springs of the FFD bodies of Dim as lines anchor → held point, with their stretch
// (length minus rest length).
template <int Dim> void AddSprings(const World& world, vtkPoints* points, vtkCellArray* lines, vtkDoubleArray* stretch) {
  for (const Spring& sp : world.options().params.springs) {
    if (sp.body < 0 || sp.body >= world.num_bodies() || !world.IsFfd(sp.body, Dim)) continue;
    const Eigen::Matrix<double, Dim, 1> x = WorldPosition(world, sp.body, sp.RestLocal<Dim>(), sp.ModeMatrix<Dim>());
    const vtkIdType ids[2] = {points->InsertNextPoint(sp.anchor.data()), points->InsertNextPoint(To3(x).data())};
    lines->InsertNextCell(2, ids);
    stretch->InsertNextValue((x - sp.Anchor<Dim>()).norm() - sp.rest_length);
  }
}

}  // namespace

int SpringSource::RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector* out_vec) {
  if (!Check(Needs::kWorld)) return 0;
  vtkPolyData* out = OutputOf(out_vec);
  auto points = DoublePoints();
  auto lines = Ptr<vtkCellArray>::New();
  auto stretch = Ptr<vtkDoubleArray>::New();
  stretch->SetName("stretch");  // length minus rest length, per line
  AddSprings<2>(*world_, points, lines, stretch);
  AddSprings<3>(*world_, points, lines, stretch);
  out->SetPoints(points);
  out->SetLines(lines);
  out->GetCellData()->AddArray(stretch);
  AddTimeValue(out, world_->time());
  return 1;
}

// ---------------------------------------------------------------------------------------
vtkStandardNewMacro(TrailSource);

void TrailSource::SetTrackedPoints(const std::vector<Eigen::Vector2d>& lattice_coords) {
  tracked_ = lattice_coords;
  ClearHistory();
}

void TrailSource::ClearHistory() {
  times_.clear();
  history_.clear();
  Modified();
}

void TrailSource::Record() {
  if (!Check(Needs::kFfdBody)) return;
  std::vector<Eigen::Vector2d> now;
  for (const Eigen::Vector2d& st : tracked_) now.push_back(WorldPositionOf(*world_, Body, st));
  times_.push_back(world_->time());
  history_.push_back(std::move(now));
  Modified();
}

int TrailSource::RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector* out_vec) {
  vtkPolyData* out = OutputOf(out_vec);
  auto points = DoublePoints();
  auto lines = Ptr<vtkCellArray>::New();
  auto time = Ptr<vtkDoubleArray>::New();
  time->SetName("time");
  const int samples = int(times_.size());
  for (size_t p = 0; p < tracked_.size(); ++p) {
    if (samples == 0) break;
    lines->InsertNextCell(samples);
    for (int k = 0; k < samples; ++k) {
      const Eigen::Vector2d& x = history_[k][p];
      lines->InsertCellPoint(points->InsertNextPoint(x.x(), x.y(), 0.0));
      time->InsertNextValue(times_[k]);
    }
  }
  out->SetPoints(points);
  out->SetLines(lines);
  out->GetPointData()->AddArray(time);
  AddTimeValue(out, world_ ? world_->time() : 0.0);
  return 1;
}

// ---------------------------------------------------------------------------------------
vtkStandardNewMacro(AnchorSource);

int AnchorSource::RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector* out_vec) {
  if (!Check(Needs::kWorld)) return 0;
  vtkPolyData* out = OutputOf(out_vec);
  auto points = DoublePoints();
  auto verts = Ptr<vtkCellArray>::New();
  for (const Anchor& a : anchors_) {
    const Eigen::Vector3d x = To3(a.point.body >= 0 ? world_->PointPosition(a.point) : a.place);
    const vtkIdType id = points->InsertNextPoint(x.x(), x.y(), x.z());
    verts->InsertNextCell(1, &id);
  }
  out->SetPoints(points);
  out->SetVerts(verts);
  AddTimeValue(out, world_->time());
  return 1;
}

}  // namespace wobble::pipelines
