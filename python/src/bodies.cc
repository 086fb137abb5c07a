// FFD bodies, one Python class wobble.BodyModel for both dimensions (2D: Faloutsos 1995 ch. 4;
// 3D: a character of issue 15 with its mesh moved by the FFD): loading an object with its
// modes, and what a body is made of, as numpy arrays.
#include "bindings.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <unordered_map>

#include "wobble/analysis/conditioning.h"
#include "wobble/body/body_model.h"
#include "wobble/body/linear_body.h"
#include "wobble/body/linear_shapes.h"
#include "wobble/core/errors.h"
#include "wobble/core/limits.h"
#include "wobble/core/rotation3.h"
#include "wobble/core/types.h"
#include "wobble/fit/pose_fit.h"
#include "wobble/scene/ffd_object.h"
#ifdef WOBBLE_PYTHON_RENDER
#include "pipelines/mesh_io.h"
#endif

namespace wobble::python {
namespace {

// The object file and its modes, read as a script's load_obj and load_def would (one loader:
// scene::FfdObject), then the mode set checked as `wobble simulate` does.
// A 2D or 3D body, as the object file's `dimension` says (a 3D file's `mesh` is read by VTK's
// readers when the module has the pipelines).
py::object LoadBody(const std::string& object, const std::vector<std::string>& modes, bool check) {
  scene::FfdObject o;
#ifdef WOBBLE_PYTHON_RENDER
  o.Load(object, pipelines::ReadSurfaceMesh);
#else
  o.Load(object);  // a `mesh` line is refused: this module was built without VTK
#endif
  o.LoadModes(modes);
  const auto checked = [&](auto body) {
    if (check) CheckLoadedModeSet(*body, object);
    return WrapBody(body);
  };
  return o.dim() == 3 ? checked(o.Body<3>()) : checked(o.Body<2>());
}

// (N, Dim): one point a row.
template <int Dim> py::array_t<double> Points(const std::vector<Eigen::Matrix<double, Dim, 1>>& points) {
  py::array_t<double> out({py::ssize_t(points.size()), py::ssize_t(Dim)});
  auto a = out.mutable_unchecked<2>();
  for (size_t k = 0; k < points.size(); ++k)
    for (int c = 0; c < Dim; ++c) a(k, c) = points[k][c];
  return out;
}

// f(body) with the body of whichever dimension b holds (f returns the same type for both).
template <class F> auto Either(const PyBody& b, F&& f) { return b.b3 ? f(*b.b3) : f(*b.b2); }

// wobble.DeformationMode: a mode of either dimension, copied (a body's modes are few and small).
struct PyMode {
  std::string name, source;
  double stiffness = 0, damping = 0;
  bool active = false;
  Eigen::MatrixXd displacement;  // (control points, Dim)
};
template <int Dim> PyMode ModeOf(const DeformationModeN<Dim>& d) {
  PyMode out{d.name, d.source, d.stiffness, d.damping, d.active, Eigen::MatrixXd(d.displacement.size(), Dim)};
  for (size_t c = 0; c < d.displacement.size(); ++c) out.displacement.row(Eigen::Index(c)) = d.displacement[c].transpose();
  return out;
}

// (N, Dim) world positions of the mass points at q (None: 0), as the fits place them.
template <int Dim> py::array_t<double> MassPointsAt(const BodyModelN<Dim>& b, const py::object& q_in) {
  const int n = b.num_q();
  const Eigen::VectorXd q = q_in.is_none() ? Eigen::VectorXd::Zero(n) : AsVector(q_in, n, "q");
  std::vector<Eigen::Matrix<double, Dim, 1>> x;
  for (int k = 0; k < b.num_points(); ++k)
    x.push_back(fit::PointPosition(fit::BasisOf<Dim>(b, k, Eigen::Matrix<double, Dim, 1>::Zero()), q));
  return Points(x);
}

// One wobble.BodyModel a body while Python holds one (the object pybind11 finds for a live
// PyBody): the same object comes back from World.body, SynthesisProblem.body, ... as went in.
// Keyed by the body; the entries of dead objects are swept as the table grows (with the GIL).
template <int Dim> py::object Wrap(std::shared_ptr<const BodyModelN<Dim>> body) {
  if (!body) return py::none();
  static std::unordered_map<const void*, std::weak_ptr<PyBody>> live;
  static size_t sweep_at = 64;
  std::weak_ptr<PyBody>& slot = live[body.get()];
  std::shared_ptr<PyBody> held = slot.lock();
  if (!held) {
    held = std::make_shared<PyBody>();
    if constexpr (Dim == 2) held->b2 = std::move(body);
    else held->b3 = std::move(body);
    slot = held;
    if (live.size() >= sweep_at) {
      for (auto it = live.begin(); it != live.end();) it = it->second.expired() ? live.erase(it) : std::next(it);
      sweep_at = 2 * live.size() + 64;
    }
  }
  return py::cast(held);
}

// The body's drawing at q: each polyline of the object file sampled `samples` times a segment
// in lattice coordinates and carried by the FFD, x = t + R(θ) (b0 + B γ) (Eq. 4.4): straight
// lines bend with the lattice.
std::vector<Eigen::MatrixXd> Outline(const BodyModel& body, const py::object& q_in, int samples) {
  if (samples < 1 || samples > 1000) throw InputError("samples_per_segment must be 1 to 1000");
  Eigen::VectorXd q = Eigen::VectorXd::Zero(body.num_q());
  if (!q_in.is_none()) {
    auto a = AsMatrix(q_in, body.num_q(), -1, "q");
    q = Eigen::Map<const Eigen::VectorXd>(a.data(), body.num_q());
  }
  const Eigen::Matrix2d R = Rotation(q[2]);
  const Eigen::VectorXd gamma = q.tail(body.num_modes());
  std::vector<Eigen::MatrixXd> out;
  for (const Polyline& pl : body.def().shapes) {
    const int np = int(pl.points.size());
    if (np < 2) continue;
    const int segments = pl.closed ? np : np - 1;
    Eigen::MatrixXd xy(segments * samples + 1, 2);
    int row = 0;
    auto put = [&](const Eigen::Vector2d& p) {
      Eigen::Vector2d b0;
      Mat2D<double> B;
      body.LocalBasis(body.lattice().LocalCoords(p), &b0, &B);
      xy.row(row++) = (q.head<2>() + R * (b0 + B * gamma)).transpose();
    };
    for (int seg = 0; seg < segments; ++seg) {
      const Eigen::Vector2d a = pl.points[seg], b = pl.points[(seg + 1) % np];
      for (int k = 0; k < samples; ++k) put(a + (b - a) * (double(k) / samples));
    }
    put(pl.closed ? pl.points.front() : pl.points.back());
    out.push_back(xy);
  }
  return out;
}

LinearOrder ParseOrder(const std::string& order) {
  if (order == "affine") return LinearOrder::kAffine;
  if (order == "quadratic") return LinearOrder::kQuadratic;
  throw InputError("order: '" + order + "' is not affine or quadratic");
}

int CheckDim(int dim) {
  if (dim != 2 && dim != 3) throw InputError("dim must be 2 or 3, got " + std::to_string(dim));
  return dim;
}

// A grid of per_side^dim points (pyramids: per level), within kMaxLinearPoints.
int CheckPerSide(int per_side, int dim, double layers) {
  CheckedCount(std::pow(double(per_side), dim) * layers, 1, kMaxLinearPoints, "the body's mass points");
  if (per_side < 2) throw InputError("per_side must be at least 2");
  return per_side;
}

std::shared_ptr<LinearBodyModel> Linear(LinearBodyDef def) { return std::make_shared<LinearBodyModel>(std::move(def)); }

}  // namespace

py::object WrapBody(std::shared_ptr<const BodyModelN<2>> body) { return Wrap<2>(std::move(body)); }
py::object WrapBody(std::shared_ptr<const BodyModelN<3>> body) { return Wrap<3>(std::move(body)); }

Eigen::VectorXd VectorOr(const py::object& v, long n, const Eigen::VectorXd& otherwise, const std::string& what) {
  if (v.is_none()) return otherwise;
  auto a = AsMatrix(v, n, -1, what);
  Eigen::VectorXd out = Eigen::Map<const Eigen::VectorXd>(a.data(), n);
  if (!out.allFinite()) throw InputError(what + " must be finite");
  return out;
}

py::array_t<double, py::array::c_style> AsMatrix(const py::handle& h, long rows, long cols, const std::string& what) {
  auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(h);
  if (!a) throw InputError(what + ": expected an array of numbers");
  const bool vector = cols < 0;
  const bool shape_ok = vector ? (a.ndim() == 1 && a.shape(0) == rows)
                               : (a.ndim() == 2 && a.shape(0) == rows && a.shape(1) == cols);
  if (!shape_ok) {
    std::string got = "(";
    for (py::ssize_t i = 0; i < a.ndim(); ++i) got += (i ? ", " : "") + std::to_string(a.shape(i));
    got += a.ndim() == 1 ? ",)" : ")";
    const std::string want =
        vector ? "(" + std::to_string(rows) + ",)" : "(" + std::to_string(rows) + ", " + std::to_string(cols) + ")";
    throw InputError(what + ": expected shape " + want + ", got " + got);
  }
  return a;
}

Eigen::VectorXd AsVector(const py::handle& h, long n, const std::string& what) {
  auto a = AsMatrix(h, n, -1, what);
  return Eigen::Map<const Eigen::VectorXd>(a.data(), n);
}

void BindBodies(py::module_& m) {
  py::class_<PyMode>(m, "DeformationMode",
                     "One user-drawn deformation mode (thesis §4.3) and its PD constants, of a 2D or a 3D body.")
      .def_readonly("name", &PyMode::name)
      .def_readonly("stiffness", &PyMode::stiffness, "K of the mode potential V = K γ²")
      .def_readonly("damping", &PyMode::damping, "c of the mode damping Q = −c γ̇")
      .def_readonly("active", &PyMode::active, "driven by a controller (chapter 5)")
      .def_readonly("source", &PyMode::source, "FILE:LINE it was read from")
      .def_property_readonly(
          "displacement", [](const PyMode& d) { return Eigen::MatrixXd(d.displacement); },
          "(num_s·num_t, 2) control-point displacements, index i·num_t + j; of a 3D body\n"
          "(num_s·num_t·num_u, 3), index (i·num_t + j)·num_u + k")
      .def("__repr__", [](const PyMode& d) { return "<DeformationMode " + d.name + ">"; });

  py::class_<PyBody, std::shared_ptr<PyBody>>(
      m, "BodyModel",
      "An FFD character of either dimension (dim): a Bernstein (or B-spline) lattice, mass points and\n"
      "deformation modes. Immutable. 2D (Faloutsos 1995 ch. 4): q = [tx, ty, θ, γ1..γD] (Eq. 4.4).\n"
      "3D (issue 15): a trivariate lattice, modes made by generators and optionally a user's mesh;\n"
      "in a World its q is [tx, ty, tz, rx, ry, rz, γ1..γD] (r the rotation vector) and q̇\n"
      "[vx, vy, vz, ωx, ωy, ωz (body frame), γ̇1..γ̇D]. Make one with wobble.load_body (a\n"
      "'dimension 3' object file gives a 3D one). What needs one dimension (outline: 2D; the mesh: 3D)\n"
      "raises InputError on the other.")
      .def_property_readonly("name", &PyBody::name)
      .def_property_readonly("dim", &PyBody::dim, "2 or 3: the dimension of the lattice, points and q")
      .def_property_readonly("num_modes", [](const PyBody& b) { return Either(b, [](const auto& x) { return x.num_modes(); }); })
      .def_property_readonly("num_q", [](const PyBody& b) { return Either(b, [](const auto& x) { return x.num_q(); }); },
                             "3 rigid coordinates (3D: 6) + one per mode")
      .def_property_readonly("num_points", [](const PyBody& b) { return Either(b, [](const auto& x) { return x.num_points(); }); },
                             "mass points")
      .def_property_readonly("modes",
                             [](const PyBody& b) {
                               return Either(b, [](const auto& x) {
                                 std::vector<PyMode> modes;
                                 for (const auto& d : x.modes()) modes.push_back(ModeOf(d));
                                 return modes;
                               });
                             })
      .def_property_readonly("mode_names",
                             [](const PyBody& b) {
                               return Either(b, [](const auto& x) {
                                 std::vector<std::string> names;
                                 for (const auto& d : x.modes()) names.push_back(d.name);
                                 return names;
                               });
                             })
      .def_property_readonly("total_mass", [](const PyBody& b) { return Either(b, [](const auto& x) { return x.moments().m; }); })
      .def_property_readonly(
          "masses",
          [](const PyBody& b) {
            return Either(b, [](const auto& x) { return py::array_t<double>(x.def().masses.size(), x.def().masses.data()); });
          },
          "(num_points,) the mass of each point")
      .def_property_readonly("mass_positions",
                             [](const PyBody& b) { return Either(b, [](const auto& x) { return Points(x.def().mass_positions); }); },
                             "(num_points, dim) mass points in the body frame")
      .def_property_readonly("rest_control",
                             [](const PyBody& b) { return Either(b, [](const auto& x) { return Points(x.rest_control()); }); },
                             "(num_s·num_t, 2) control points of the undeformed lattice (3D: (num_s·num_t·num_u, 3);\n"
                             "the index as DeformationMode.displacement's)")
      .def_property_readonly("lattice_shape",
                             [](const PyBody& b) {
                               return Either(b, [](const auto& x) {
                                 py::tuple shape(x.lattice().dim());
                                 for (int a = 0; a < x.lattice().dim(); ++a) shape[a] = x.lattice().num(a);
                                 return shape;
                               });
                             },
                             "control points per axis: (num_s, num_t), 3D (num_s, num_t, num_u)")
      .def(
          "outline", [](const PyBody& b, const py::object& q, int samples) { return Outline(b.Need<2>("outline"), q, samples); },
          py::arg("q") = py::none(), py::arg("samples_per_segment") = 8,
          "The drawing at q (None: at rest) as world-space polylines, each (M, 2), bent by the FFD.\n"
          "2D bodies only (InputError for a 3D one: its mesh_vertices(q) is its drawing).")
      .def_property_readonly("mesh_points", [](const PyBody& b) { return Points(b.Need<3>("mesh_points").def().mesh.points); },
                             "(V, 3) the mesh's vertices in the body frame (V = 0 without a mesh); 3D bodies only")
      .def_property_readonly(
          "mesh_triangles",
          [](const PyBody& b) {
            const auto& t = b.Need<3>("mesh_triangles").def().mesh.triangles;
            py::array_t<int> out({py::ssize_t(t.size()), py::ssize_t(3)});
            auto a = out.mutable_unchecked<2>();
            for (size_t k = 0; k < t.size(); ++k)
              for (int c = 0; c < 3; ++c) a(k, c) = t[k][size_t(c)];
            return out;
          },
          "(T, 3) vertex indices of each triangle; 3D bodies only")
      .def(
          "mesh_vertices",
          [](const PyBody& body, const py::object& q_in) {
            const BodyModelN<3>& b = body.Need<3>("mesh_vertices");
            const int n = b.num_q();
            const Eigen::VectorXd q = q_in.is_none() ? Eigen::VectorXd::Zero(n) : AsVector(q_in, n, "q");
            const Eigen::Quaterniond R = ExpRotation<double>(Eigen::Vector3d(q.segment<3>(3)));
            const Eigen::VectorXd gamma = q.tail(b.num_modes());
            std::vector<Eigen::Vector3d> x(b.def().mesh.points.size());
            for (size_t v = 0; v < x.size(); ++v)
              x[v] = q.head<3>() + R * (b.mesh_rest_local(int(v)) + b.mesh_mode_matrix(int(v)) * gamma);
            return Points(x);
          },
          py::arg("q") = py::none(),
          "(V, 3) world positions of the mesh's vertices at q: x = t + R (b0 + B γ), every vertex\n"
          "moved by the FFD of its lattice; 3D bodies only")
      .def(
          "mass_points_at",
          [](const PyBody& b, const py::object& q) { return Either(b, [&](const auto& x) { return MassPointsAt(x, q); }); },
          py::arg("q") = py::none(),
          "(N, dim) world positions of the mass points at q (2D: [t, θ, γ]; 3D: [t, r, γ], r a rotation\n"
          "vector), as the fits place them (the correspondences of wobble.fit_pose with mass_points)")
      .def("__repr__", [](const PyBody& b) {
        const std::string head = "<BodyModel '" + b.name() + "' (" + std::to_string(b.dim()) + "D): ";
        return Either(b, [&](const auto& x) {
          std::string out = head + std::to_string(x.num_points()) + " mass points, " + std::to_string(x.num_modes()) + " modes";
          if (b.dim() == 3) out += ", " + std::to_string(x.def().mesh.points.size()) + " mesh vertices";
          return out + ">";
        });
      });
  // the 3D class's old name: wobble.BodyModel3 (python/wobble/__init__.py) warns and gives BodyModel

  py::class_<LinearBodyModel, std::shared_ptr<LinearBodyModel>>(
      m, "LinearBodyModel",
      "A Witkin & Welch body (1990 §3): x = R p(u) with p affine [u, 1] or quadratic, the constant mass\n"
      "matrix M = Σ m_k p(u_k) p(u_k)ᵀ (Eq. 5) inverted once. Make one with linear_box, linear_pyramid\n"
      "or linear_body.")
      .def_property_readonly("name", &LinearBodyModel::name)
      .def_property_readonly("dim", &LinearBodyModel::dim)
      .def_property_readonly("order", [](const LinearBodyModel& b) { return b.order() == LinearOrder::kAffine ? "affine" : "quadratic"; })
      .def_property_readonly("basis_size", &LinearBodyModel::basis_size, "n: the columns of R")
      .def_property_readonly("num_points", &LinearBodyModel::num_points)
      .def_property_readonly("total_mass", &LinearBodyModel::total_mass)
      .def_property_readonly("mass_matrix", &LinearBodyModel::mass_matrix, "M (n x n), Eq. 5")
      .def_property_readonly("points",
                             [](const LinearBodyModel& b) {
                               Eigen::MatrixXd u(b.num_points(), b.dim());
                               for (int k = 0; k < b.num_points(); ++k) u.row(k) = b.def().points[k].transpose();
                               return u;
                             },
                             "(num_points, dim) undeformed coordinates u_k")
      .def_property_readonly("masses", [](const LinearBodyModel& b) { return b.def().masses; })
      .def("rest_state", &LinearBodyModel::RestState, "R of the rest shape: [I | 0 | 0]")
      .def("__repr__", [](const LinearBodyModel& b) {
        return "<LinearBodyModel " + b.name() + ": " + std::to_string(b.dim()) + "D, " + std::to_string(b.num_points()) +
               " mass points>";
      });

  m.def(
      "linear_box",
      [](int dim, const Eigen::VectorXd& half_extents, int per_side, double mass, const std::string& order,
         const std::string& name) {
        CheckPerSide(per_side, CheckDim(dim), 1);
        if (half_extents.size() != dim || !(half_extents.array() > 0).all() || !half_extents.allFinite())
          throw InputError("half_extents: expected " + std::to_string(dim) + " finite numbers > 0");
        if (!(mass > 0) || !std::isfinite(mass)) throw InputError("mass must be a finite number > 0");
        return Linear(MakeBoxBody(name, dim, ParseOrder(order), half_extents, per_side, mass));
      },
      py::arg("dim"), py::arg("half_extents"), py::kw_only(), py::arg("per_side") = 2, py::arg("mass") = 1.0,
      py::arg("order") = "affine", py::arg("name") = "box",
      "A box [-half, half] filled with per_side points per axis, equal masses summing to `mass`.");
  m.def(
      "linear_pyramid",
      [](int dim, double half_width, double height, int levels, int per_side, double mass, const std::string& order,
         const std::string& name) {
        CheckPerSide(per_side, CheckDim(dim), std::max(levels, 1));
        if (!(mass > 0) || !std::isfinite(mass)) throw InputError("mass must be a finite number > 0");
        return Linear(MakePyramidBody(name, dim, ParseOrder(order), half_width, height, levels, per_side, mass));
      },
      py::arg("dim"), py::arg("half_width"), py::arg("height"), py::kw_only(), py::arg("levels") = 3,
      py::arg("per_side") = 2, py::arg("mass") = 1.0, py::arg("order") = "affine", py::arg("name") = "pyramid",
      "A pyramid (2D: a triangle) of `levels` point layers and an apex, as Witkin & Welch's Fig. 3.");
  m.def(
      "linear_body",
      [](const Eigen::MatrixXd& points, const std::vector<double>& masses, const std::string& order, const std::string& name) {
        LinearBodyDef def;
        def.name = name;
        def.dim = CheckDim(int(points.cols()));
        def.order = ParseOrder(order);
        if (long(masses.size()) != points.rows())
          throw InputError("masses: expected " + std::to_string(points.rows()) + " masses, one per point");
        CheckedCount(double(points.rows()), 1, kMaxLinearPoints, "the body's mass points");
        for (int k = 0; k < points.rows(); ++k) def.points.push_back(points.row(k).transpose());
        def.masses = masses;
        return Linear(std::move(def));
      },
      py::arg("points"), py::arg("masses"), py::kw_only(), py::arg("order") = "affine", py::arg("name") = "body",
      "A linear body from its mass points (K, dim) and masses (K,) (InputError when M is singular).");

  m.def("load_body", &LoadBody, py::arg("object"), py::arg("modes") = std::vector<std::string>(),
        py::arg("check") = true,
        "Reads an object file (.obj: lattice, mass points, drawing; 'dimension 3': a 3D lattice or\n"
        "'lattice fit', 'sample', a 'mesh') and its deformation files, the modes of all files in\n"
        "order; returns a BodyModel (its dim 2 or 3). check: refuse a mode set that cannot be simulated\n"
        "(InputError, as `wobble simulate`), and warn about a poorly conditioned one.\n"
        "Errors name FILE:LINE (wobble.ParseError).");
  BindDeprecated(m, "load_body3", "load_body");  // release 0.1's name: load_body reads either
}

}  // namespace wobble::python
