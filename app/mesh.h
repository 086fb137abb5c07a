// `wobble mesh`: writes the meshes wobble ships (pipelines/mesh_io.h: the table built from
// boxes, the pot revolved from the 2D pot's outline), and reports any mesh file's size, area,
// enclosed volume and bounds, as wobble reads it.
#pragma once

#include <CLI/CLI.hpp>
#include <string>

namespace wobble::app {

struct MeshArgs {
  std::string make;  // table | pot
  std::string out;   // .vtp .obj .stl .ply
  std::string info;  // a mesh file to describe
};
CLI::App* AddMeshCommand(CLI::App* app, MeshArgs* args);
int RunMesh(const MeshArgs& args);

}  // namespace wobble::app
