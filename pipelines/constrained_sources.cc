#include "pipelines/constrained_sources.h"

#include <vtkCellArray.h>
#include <vtkDoubleArray.h>
#include <vtkFieldData.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkObjectFactory.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>

namespace wobble::pipelines {
namespace {

template <class T> using Ptr = vtkSmartPointer<T>;

vtkPolyData* OutputOf(vtkInformationVector* out) {
  return vtkPolyData::SafeDownCast(out->GetInformationObject(0)->Get(vtkDataObject::DATA_OBJECT()));
}

void AddTimeValue(vtkPolyData* out, double time) {
  auto t = Ptr<vtkDoubleArray>::New();
  t->SetName("TimeValue");
  t->InsertNextValue(time);
  out->GetFieldData()->AddArray(t);
}

Eigen::Vector3d To3(const Eigen::VectorXd& x) {
  return Eigen::Vector3d(x[0], x[1], x.size() > 2 ? x[2] : 0.0);
}

Ptr<vtkDoubleArray> Vectors(const char* name, vtkIdType n) {
  auto a = Ptr<vtkDoubleArray>::New();
  a->SetName(name);
  a->SetNumberOfComponents(3);
  a->SetNumberOfTuples(n);
  return a;
}

// The box the body's mass points span in undeformed coordinates.
void UndeformedBox(const LinearBodyModel& model, Eigen::VectorXd* lo, Eigen::VectorXd* hi) {
  *lo = model.def().points[0];
  *hi = *lo;
  for (const Eigen::VectorXd& u : model.def().points) {
    *lo = lo->cwiseMin(u);
    *hi = hi->cwiseMax(u);
  }
}

}  // namespace

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

void ConstrainedSourceBase::PrintSelf(ostream& os, vtkIndent indent) {
  Superclass::PrintSelf(os, indent);
  os << indent << "World: " << world_ << "\n" << indent << "Body: " << Body << "\n";
}

bool ConstrainedSourceBase::CheckLinearBody() {
  if (!world_) {
    vtkErrorMacro("no world set");
    return false;
  }
  if (Body < 0 || Body >= world_->num_bodies() || world_->kind(Body) != BodyKind::kLinear) {
    vtkErrorMacro("body " << Body << " is not a linear body of the world");
    return false;
  }
  return true;
}

// ---------------------------------------------------------------------------------------
vtkStandardNewMacro(LinearBoxSource);

int LinearBoxSource::RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector* out_vec) {
  if (!CheckLinearBody()) return 0;
  vtkPolyData* out = OutputOf(out_vec);
  const LinearBodyModel& model = world_->linear_model(Body);
  const int d = model.dim();
  Eigen::VectorXd lo, hi;
  UndeformedBox(model, &lo, &hi);
  auto level = [&](int axis, int k) { return lo[axis] + 0.5 * k * (hi[axis] - lo[axis]); };  // k = 0, 1, 2

  auto points = Ptr<vtkPoints>::New();
  points->SetDataTypeToDouble();
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
  AddTimeValue(out, world_->time());
  return 1;
}

// ---------------------------------------------------------------------------------------
vtkStandardNewMacro(LinearMassPointSource);

int LinearMassPointSource::RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector* out_vec) {
  if (!CheckLinearBody()) return 0;
  vtkPolyData* out = OutputOf(out_vec);
  const LinearBodyModel& model = world_->linear_model(Body);
  const Eigen::MatrixXd& R = world_->linear_R(Body);
  const Eigen::MatrixXd& R_dot = world_->linear_R_dot(Body);
  const int n = model.num_points();
  auto points = Ptr<vtkPoints>::New();
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(n);
  auto mass = Ptr<vtkDoubleArray>::New();
  mass->SetName("mass");
  mass->SetNumberOfTuples(n);
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
  AddTimeValue(out, world_->time());
  return 1;
}

// ---------------------------------------------------------------------------------------
vtkStandardNewMacro(LinearShapeSource);

int LinearShapeSource::RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector* out_vec) {
  if (!CheckLinearBody()) return 0;
  vtkPolyData* out = OutputOf(out_vec);
  const int d = world_->linear_model(Body).dim();
  if (drawing_.dim() != 0 && drawing_.dim() != d) {
    vtkErrorMacro("the drawing is " << drawing_.dim() << "D, the body " << d << "D");
    return 0;
  }
  auto points = Ptr<vtkPoints>::New();
  points->SetDataTypeToDouble();
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
  AddTimeValue(out, world_->time());
  return 1;
}

// ---------------------------------------------------------------------------------------
vtkStandardNewMacro(AnchorSource);

int AnchorSource::RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector* out_vec) {
  if (!world_) {
    vtkErrorMacro("no world set");
    return 0;
  }
  vtkPolyData* out = OutputOf(out_vec);
  auto points = Ptr<vtkPoints>::New();
  points->SetDataTypeToDouble();
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
