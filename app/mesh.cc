#include "mesh.h"

#include <Eigen/Geometry>
#include <cstdio>
#include <iostream>

#include "cli_common.h"
#include "pipelines/mesh_io.h"

namespace wobble::app {
namespace {

void Describe(const std::string& what, const SurfaceMesh& mesh) {
  Eigen::AlignedBox3d box;
  for (const Eigen::Vector3d& p : mesh.points) box.extend(p);
  std::printf("%s: %zu points, %zu triangles; area %.6g, enclosed volume %.6g; bounds [%.4g %.4g %.4g] .. [%.4g %.4g %.4g]\n",
              what.c_str(), mesh.points.size(), mesh.triangles.size(), SurfaceArea(mesh), EnclosedVolume(mesh),
              box.min().x(), box.min().y(), box.min().z(), box.max().x(), box.max().y(), box.max().z());
}

}  // namespace

CLI::App* AddMeshCommand(CLI::App* app, MeshArgs* a) {
  CLI::App* cmd = app->add_subcommand("mesh", "Make the meshes wobble ships (table, pot) or describe a mesh file");
  cmd->add_option("--make", a->make, "table (five boxes) | pot (the 2D pot's outline revolved)")->type_name("NAME");
  cmd->add_option("--out", a->out, "Where --make writes (.vtp, .obj, .stl or .ply)")->type_name("FILE");
  cmd->add_option("--info", a->info, "Describe a mesh file (.obj, .stl, .ply, .vtp) as wobble reads it")->type_name("FILE");
  cmd->footer(
      "Examples:\n"
      "  wobble mesh --make pot --out data/pot3.vtp\n"
      "  wobble mesh --info data/pot3.vtp");
  return cmd;
}

int RunMesh(const MeshArgs& a) {
  if (a.make.empty() == a.info.empty()) throw UsageError("mesh: give either --make NAME --out FILE or --info FILE");
  if (!a.info.empty()) {
    Describe(a.info, pipelines::ReadSurfaceMesh(a.info));
    return kExitOk;
  }
  if (a.out.empty()) throw UsageError("mesh --make: --out FILE is required");
  CheckOutputFile("--out", a.out);
  SurfaceMesh mesh;
  if (a.make == "table") mesh = pipelines::MakeTableMesh();
  else if (a.make == "pot") mesh = pipelines::MakePotMesh();
  else throw UsageError("mesh --make: '" + a.make + "' is not one of table, pot");
  pipelines::WriteSurfaceMesh(a.out, mesh);
  Describe(a.out, mesh);
  return kExitOk;
}

}  // namespace wobble::app
