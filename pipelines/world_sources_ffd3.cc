// The 3D FFD body's parts (issue 15), for the sources of world_sources.h: its deformed
// control lattice, its mass points, and its drawing (the user's mesh with every vertex moved
// by the FFD, and its polylines), all in world coordinates x = t + R (b0 + B γ).
#include <vtkCellArray.h>
#include <vtkDoubleArray.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkUnsignedCharArray.h>

#include "pipelines/world_sources.h"

namespace wobble::pipelines {
namespace {

template <class T> using Ptr = vtkSmartPointer<T>;

Ptr<vtkDoubleArray> Array(const char* name, int components, vtkIdType n) {
  auto a = Ptr<vtkDoubleArray>::New();
  a->SetName(name);
  a->SetNumberOfComponents(components);
  a->SetNumberOfTuples(n);
  return a;
}

Ptr<vtkPoints> DoublePoints(vtkIdType n) {
  auto points = Ptr<vtkPoints>::New();
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(n);
  return points;
}

}  // namespace

Eigen::Vector3d WorldPosition3(const World& world, int body, const Eigen::Vector3d& b0, const Mat3D<double>& B) {
  const BodyState<3, double>& s = world.state<3>(body);
  return s.translation() + s.orientation() * (b0 + B * s.gamma());
}

Eigen::AlignedBox3d BodyBounds3(const World& world, int body) {
  const BodyModel3& m = world.body<3>(body);
  const BodyState<3, double>& s = world.state<3>(body);
  Eigen::AlignedBox3d box;
  for (int c = 0; c < m.lattice().size(); ++c) {
    Eigen::Vector3d l = m.rest_control()[size_t(c)];
    for (int d = 0; d < m.num_modes(); ++d) l += m.modes()[size_t(d)].displacement[size_t(c)] * s.gamma()[d];
    box.extend(s.translation() + s.orientation() * l);
  }
  return box;
}

bool LatticeSource::DrawFfd3(vtkPolyData* out) {
  const BodyModel3& body = world_->body<3>(Body);
  const BodyState<3, double>& s = world_->state<3>(Body);
  const Lattice3& lat = body.lattice();
  const int n = lat.size();
  auto points = DoublePoints(n);
  auto rest = Array("rest_position", 3, n);
  auto disp = Array("displacement", 3, n);
  for (int c = 0; c < n; ++c) {
    Eigen::Vector3d d = Eigen::Vector3d::Zero();  // Σ γ_d d^d_ijk (Eq. 4.2 in 3D), body frame
    for (int m = 0; m < body.num_modes(); ++m) d += body.modes()[size_t(m)].displacement[size_t(c)] * s.gamma()[m];
    const Eigen::Vector3d& r = body.rest_control()[size_t(c)];
    const Eigen::Vector3d x = s.translation() + s.orientation() * (r + d);
    points->SetPoint(c, x.data());
    rest->SetTuple(c, r.data());
    disp->SetTuple(c, d.data());
  }
  auto verts = Ptr<vtkCellArray>::New();
  for (vtkIdType c = 0; c < n; ++c) verts->InsertNextCell(1, &c);
  // a line along each axis through every row of control points
  auto lines = Ptr<vtkCellArray>::New();
  const Lattice3::Sizes size = lat.sizes();
  for (int axis = 0; axis < 3; ++axis) {
    const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
    for (int i = 0; i < size[size_t(a1)]; ++i)
      for (int j = 0; j < size[size_t(a2)]; ++j) {
        lines->InsertNextCell(size[size_t(axis)]);
        for (int k = 0; k < size[size_t(axis)]; ++k) {
          Lattice3::Cell cell;
          cell[size_t(axis)] = k, cell[size_t(a1)] = i, cell[size_t(a2)] = j;
          lines->InsertCellPoint(lat.FlatIndex(cell));
        }
      }
  }
  out->SetPoints(points);
  out->SetVerts(verts);
  out->SetLines(lines);
  out->GetPointData()->AddArray(rest);
  out->GetPointData()->AddArray(disp);
  return true;
}

bool MassPointSource::DrawFfd3(vtkPolyData* out) {
  const BodyModel3& body = world_->body<3>(Body);
  const BodyState<3, double>& s = world_->state<3>(Body);
  const Eigen::Matrix3d R = s.orientation().toRotationMatrix();
  const WorldOptions& o = world_->options();
  const int n = body.num_points();
  const int D = body.num_modes();
  auto points = DoublePoints(n);
  auto mass = Array("mass", 1, n);
  auto velocity = Array("velocity", 3, n);
  auto force = Array("applied_force", 3, n);
  auto contact = Ptr<vtkUnsignedCharArray>::New();
  contact->SetName("in_contact");
  contact->SetNumberOfTuples(n);
  contact->FillValue(0);
  for (const Contact<3, double>& c : s.contacts) contact->SetValue(c.point, 1);
  auto verts = Ptr<vtkCellArray>::New();
  const Eigen::Vector3d v_t = s.qd.head<3>(), omega = s.qd.segment<3>(3);
  const size_t count = size_t(n);
  std::vector<Eigen::Vector3d> x(count), v(count), f(count);
  for (int k = 0; k < n; ++k) {
    const auto B = body.mode_matrix(k);
    const Eigen::Vector3d l = body.rest_local(k) + B * s.gamma();
    x[size_t(k)] = s.translation() + R * l;
    // ẋ = ṫ + R (ω × l + B γ̇): J v of kinematics3.h, body-frame ω
    v[size_t(k)] = v_t + R * (omega.cross(l) + B * s.qd.tail(D));
    f[size_t(k)] = o.params.gravity_on ? Eigen::Vector3d(body.mass(k) * o.gravity_3d) : Eigen::Vector3d::Zero();
  }
  // the ground's penalty and capped friction on every point tied to it (§4.9, step3.h)
  if (o.ground_3d.enabled)
    for (const Contact<3, double>& c : s.contacts) {
      bool slipping;
      const size_t k = size_t(c.point);
      f[k] += GroundForce<double>(o.ground_3d.Face(c.face, x[k]), x[k], v[k], c.anchor, &slipping);
    }
  for (vtkIdType k = 0; k < n; ++k) {
    points->SetPoint(k, x[size_t(k)].data());
    mass->SetValue(k, body.mass(int(k)));
    velocity->SetTuple(k, v[size_t(k)].data());
    force->SetTuple(k, f[size_t(k)].data());
    verts->InsertNextCell(1, &k);
  }
  out->SetPoints(points);
  out->SetVerts(verts);
  for (vtkDataArray* a : {static_cast<vtkDataArray*>(mass), static_cast<vtkDataArray*>(velocity),
                          static_cast<vtkDataArray*>(force), static_cast<vtkDataArray*>(contact)})
    out->GetPointData()->AddArray(a);
  return true;
}

bool ShapeSource::DrawFfd3(vtkPolyData* out) {
  const BodyModel3& body = world_->body<3>(Body);
  const BodyState<3, double>& s = world_->state<3>(Body);
  const Eigen::Matrix3d R = s.orientation().toRotationMatrix();
  const SurfaceMesh& mesh = body.def().mesh;
  auto points = Ptr<vtkPoints>::New();
  points->SetDataTypeToDouble();
  auto disp = Ptr<vtkDoubleArray>::New();  // B γ per point, body frame: the deformation alone
  disp->SetName("displacement");
  disp->SetNumberOfComponents(3);
  auto add = [&](const Eigen::Vector3d& b0, const Eigen::Ref<const Mat3D<double>>& B) {
    const Eigen::Vector3d d = B * s.gamma();
    const Eigen::Vector3d x = s.translation() + R * (b0 + d);
    disp->InsertNextTuple(d.data());
    return points->InsertNextPoint(x.data());
  };
  // the mesh: its vertices' bases were made once, with the body (BodyModel3::mesh_rest_local)
  auto polys = Ptr<vtkCellArray>::New();
  if (Surface && !mesh.empty()) {
    for (int v = 0; v < int(mesh.points.size()); ++v) add(body.mesh_rest_local(v), body.mesh_mode_matrix(v));
    for (const std::array<int, 3>& t : mesh.triangles) {
      const vtkIdType ids[3] = {t[0], t[1], t[2]};
      polys->InsertNextCell(3, ids);
    }
  }
  // the polylines, each segment cut into SamplesPerSegment pieces
  auto lines = Ptr<vtkCellArray>::New();
  if (Lines) {
    for (const PolylineN<3>& pl : body.def().shapes) {
      const int np = int(pl.points.size());
      if (np < 2) continue;
      const int segments = pl.closed ? np : np - 1;
      std::vector<vtkIdType> ids;
      for (int seg = 0; seg < segments; ++seg)
        for (int k = 0; k < SamplesPerSegment + (seg + 1 == segments && !pl.closed ? 1 : 0); ++k) {
          const Eigen::Vector3d a = pl.points[size_t(seg)], b = pl.points[size_t((seg + 1) % np)];
          Eigen::Vector3d b0;
          Mat3D<double> B;
          body.LocalBasis(body.lattice().LocalCoords(a + (b - a) * (double(k) / SamplesPerSegment)), &b0, &B);
          ids.push_back(add(b0, B));
        }
      if (pl.closed) ids.push_back(ids.front());
      lines->InsertNextCell(vtkIdType(ids.size()), ids.data());
    }
  }
  out->SetPoints(points);
  out->SetPolys(polys);
  out->SetLines(lines);
  out->GetPointData()->AddArray(disp);
  return true;
}

}  // namespace wobble::pipelines
