#include "pipelines/mesh_io.h"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <stdexcept>
#include <vtkAlgorithm.h>
#include <vtkAppendPolyData.h>
#include <vtkCallbackCommand.h>
#include <vtkCellArray.h>
#include <vtkCleanPolyData.h>
#include <vtkCommand.h>
#include <vtkCubeSource.h>
#include <vtkOBJReader.h>
#include <vtkOBJWriter.h>
#include <vtkPLYReader.h>
#include <vtkPLYWriter.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkRotationalExtrusionFilter.h>
#include <vtkSTLReader.h>
#include <vtkSTLWriter.h>
#include <vtkSmartPointer.h>
#include <vtkTransform.h>
#include <vtkTransformPolyDataFilter.h>
#include <vtkTriangleFilter.h>
#include <vtkXMLPolyDataReader.h>
#include <vtkXMLPolyDataWriter.h>

#include "wobble/formats/atomic_file.h"
#include "wobble/formats/object_file.h"
#include "wobble/formats/parse_error.h"

namespace wobble::pipelines {
namespace {

template <class T> using Ptr = vtkSmartPointer<T>;

std::string Extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return ext;
}

// VTK reports a reader's trouble through its output window; this keeps the text instead.
struct ErrorCatcher {
  std::string text;
  Ptr<vtkCallbackCommand> command = Ptr<vtkCallbackCommand>::New();
  explicit ErrorCatcher(vtkObject* watched) {
    command->SetClientData(this);
    command->SetCallback([](vtkObject*, unsigned long, void* self, void* call_data) {
      auto* catcher = static_cast<ErrorCatcher*>(self);
      if (catcher->text.empty() && call_data) catcher->text = static_cast<const char*>(call_data);
    });
    watched->AddObserver(vtkCommand::ErrorEvent, command);
  }
};

SurfaceMesh FromPolyData(vtkPolyData* poly) {
  SurfaceMesh mesh;
  mesh.points.resize(size_t(poly->GetNumberOfPoints()));
  for (vtkIdType i = 0; i < poly->GetNumberOfPoints(); ++i) {
    double p[3];
    poly->GetPoint(i, p);
    mesh.points[size_t(i)] = Eigen::Vector3d(p[0], p[1], p[2]);
  }
  vtkCellArray* polys = poly->GetPolys();
  const vtkIdType* ids = nullptr;
  vtkIdType n = 0;
  for (polys->InitTraversal(); polys->GetNextCell(n, ids);)
    if (n == 3) mesh.triangles.push_back({int(ids[0]), int(ids[1]), int(ids[2])});
  return mesh;
}

Ptr<vtkPolyData> ToPolyData(const SurfaceMesh& mesh) {
  auto points = Ptr<vtkPoints>::New();
  points->SetDataTypeToDouble();
  for (const Eigen::Vector3d& p : mesh.points) points->InsertNextPoint(p.x(), p.y(), p.z());
  auto polys = Ptr<vtkCellArray>::New();
  for (const std::array<int, 3>& t : mesh.triangles) {
    const vtkIdType ids[3] = {t[0], t[1], t[2]};
    polys->InsertNextCell(3, ids);
  }
  auto poly = Ptr<vtkPolyData>::New();
  poly->SetPoints(points);
  poly->SetPolys(polys);
  return poly;
}

// Triangles only, shared points merged (a revolved seam, a box's corners): what lib expects.
SurfaceMesh Triangulated(vtkAlgorithmOutput* source) {
  auto triangles = Ptr<vtkTriangleFilter>::New();
  triangles->SetInputConnection(source);
  triangles->PassLinesOff();
  triangles->PassVertsOff();
  auto clean = Ptr<vtkCleanPolyData>::New();
  clean->SetInputConnection(triangles->GetOutputPort());
  clean->ConvertPolysToLinesOff();
  clean->ConvertLinesToPointsOff();
  clean->Update();
  // merging may collapse a triangle at a pole to a line: only triangles are kept
  return FromPolyData(clean->GetOutput());
}

}  // namespace

SurfaceMesh ReadSurfaceMesh(const std::string& path) {
  const std::string kind = formats::NonRegularKind(path);
  if (!kind.empty()) throw formats::ParseError(path, 0, "is " + kind + ", not a regular file");
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw formats::ParseError(path, 0, "cannot open file: no such file");
  const std::string ext = Extension(path);
  Ptr<vtkAlgorithm> reader;
  if (ext == ".obj") {
    auto r = Ptr<vtkOBJReader>::New();
    r->SetFileName(path.c_str());
    reader = r;
  } else if (ext == ".stl") {
    auto r = Ptr<vtkSTLReader>::New();
    r->SetFileName(path.c_str());
    reader = r;
  } else if (ext == ".ply") {
    auto r = Ptr<vtkPLYReader>::New();
    r->SetFileName(path.c_str());
    reader = r;
  } else if (ext == ".vtp") {
    auto r = Ptr<vtkXMLPolyDataReader>::New();
    r->SetFileName(path.c_str());
    reader = r;
  } else {
    throw formats::ParseError(path, 0, "unknown mesh format '" + ext + "' (expected .obj, .stl, .ply or .vtp)");
  }
  ErrorCatcher errors(reader);
  SurfaceMesh mesh = Triangulated(reader->GetOutputPort());
  if (!errors.text.empty()) {
    std::string text = errors.text;
    while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back()))) text.pop_back();
    throw formats::ParseError(path, 0, "VTK cannot read it: " + text);
  }
  if (mesh.triangles.empty()) throw formats::ParseError(path, 0, "holds no triangles (a surface mesh was expected)");
  return mesh;
}

void WriteSurfaceMesh(const std::string& path, const SurfaceMesh& mesh) {
  const std::string ext = Extension(path);
  if (ext != ".vtp" && ext != ".obj" && ext != ".stl" && ext != ".ply")
    throw std::runtime_error(path + ": unknown mesh format '" + ext + "' (expected .vtp, .obj, .stl or .ply)");
  Ptr<vtkPolyData> poly = ToPolyData(mesh);
  formats::WriteFileAtomically(path, [&](const std::string& tmp) {
    int ok = 0;
    if (ext == ".vtp") {
      auto w = Ptr<vtkXMLPolyDataWriter>::New();
      w->SetFileName(tmp.c_str());
      w->SetInputData(poly);
      w->SetDataModeToAscii();  // small, and readable in a diff
      ok = w->Write();
    } else if (ext == ".obj") {
      auto w = Ptr<vtkOBJWriter>::New();
      w->SetFileName(tmp.c_str());
      w->SetInputData(poly);
      ok = w->Write();
    } else if (ext == ".stl") {
      auto w = Ptr<vtkSTLWriter>::New();
      w->SetFileName(tmp.c_str());
      w->SetInputData(poly);
      ok = w->Write();
    } else {
      // vtkPLYWriter appends ".ply" to a name that does not end in it: give it one, then move
      const std::string ply = tmp + ".ply";
      auto w = Ptr<vtkPLYWriter>::New();
      w->SetFileName(ply.c_str());
      w->SetInputData(poly);
      ok = w->Write();
      std::error_code ec;
      if (ok) std::filesystem::rename(ply, tmp, ec);
      if (ec) throw std::runtime_error("cannot rename " + ply + " to " + tmp + ": " + ec.message());
    }
    std::error_code ec;
    if (!ok || std::filesystem::file_size(tmp, ec) == 0 || ec) throw std::runtime_error("VTK could not write " + tmp);
  });
}

template <int Dim> BodyDefN<Dim> ReadObject(const std::string& path) {
  return formats::ReadObjectFile<Dim>(path, ReadSurfaceMesh);
}
template BodyDefN<2> ReadObject<2>(const std::string&);
template BodyDefN<3> ReadObject<3>(const std::string&);

SurfaceMesh MakeTableMesh() {
  auto parts = Ptr<vtkAppendPolyData>::New();
  auto box = [&](double x0, double x1, double y0, double y1, double z0, double z1) {
    auto cube = Ptr<vtkCubeSource>::New();
    cube->SetBounds(x0, x1, y0, y1, z0, z1);
    parts->AddInputConnection(cube->GetOutputPort());
  };
  box(0, 300, 80, 100, 0, 200);  // the top
  for (double x : {0.0, 280.0})
    for (double z : {0.0, 180.0}) box(x, x + 20, 0, 85, z, z + 20);  // legs, into the top by 5
  return Triangulated(parts->GetOutputPort());
}

SurfaceMesh MakePotMesh() {
  // the right half of the 2D pot's outline (data/pot.obj) as radius r = x − 100 and height y,
  // from the axis at the bottom to the axis at the top, in the x-z plane (r, ., y) so that
  // vtkRotationalExtrusionFilter can turn it about z
  const double profile[][2] = {{0, 0}, {60, 0}, {75, 120}, {100, 120}, {100, 160}, {0, 160}};
  auto points = Ptr<vtkPoints>::New();
  auto line = Ptr<vtkCellArray>::New();
  line->InsertNextCell(6);
  for (int i = 0; i < 6; ++i) line->InsertCellPoint(points->InsertNextPoint(profile[i][0], 0.0, profile[i][1]));
  auto outline = Ptr<vtkPolyData>::New();
  outline->SetPoints(points);
  outline->SetLines(line);
  auto revolve = Ptr<vtkRotationalExtrusionFilter>::New();
  revolve->SetInputData(outline);
  revolve->SetResolution(48);
  revolve->SetAngle(360.0);
  // z up to y up, the axis on the body frame's y axis (a spin about body y turns it in place)
  auto to_body = Ptr<vtkTransform>::New();
  to_body->RotateX(-90.0);  // (x, y, z) -> (x, z, -y)
  auto moved = Ptr<vtkTransformPolyDataFilter>::New();
  moved->SetInputConnection(revolve->GetOutputPort());
  moved->SetTransform(to_body);
  return Triangulated(moved->GetOutputPort());
}

}  // namespace wobble::pipelines
