// Users' meshes in and out, through VTK's readers and writers (issue 15): a 3D object file's
// `mesh` line is read here, and the meshes wobble ships (data/table3.vtp, data/pot3.vtp) are
// made here from VTK's sources and filters, never downloaded.
#pragma once

#include <string>

#include "wobble/body/body_model.h"
#include "wobble/body/surface_mesh.h"

namespace wobble::pipelines {

// Reads a triangle surface by the file's extension: .obj (vtkOBJReader), .stl (vtkSTLReader),
// .ply (vtkPLYReader), .vtp (vtkXMLPolyDataReader). Polygons and strips are split into
// triangles (vtkTriangleFilter); lines and vertices are ignored. Throws formats::ParseError
// (FILE, line 0) for a file that is missing, not a regular file, of another extension, that
// VTK cannot read (its error text is kept), or that holds no triangle.
SurfaceMesh ReadSurfaceMesh(const std::string& path);

// Writes a mesh as .vtp, .obj, .stl or .ply by the extension, atomically (temporary file,
// then rename); std::runtime_error with the reason on failure.
void WriteSurfaceMesh(const std::string& path, const SurfaceMesh& mesh);

// An object file with its mesh: formats::ReadObjectFile<Dim> with the reader above.
template <int Dim> BodyDefN<Dim> ReadObject(const std::string& path);

// The meshes wobble makes itself (`wobble mesh`), in the body frame of their object files:
// - the table of data/table3.obj built from five boxes (vtkCubeSource): a 300 x 200 top,
//   20 thick, whose upper face is at y = 100, on four 20 x 20 legs down to y = 0, x in [0, 300],
//   z in [0, 200] (each part a closed box; they overlap where the legs meet the top);
// - the pot: the 2D pot's outline of data/pot.obj (Figs. 4.10/4.11) revolved about its axis
//   with vtkRotationalExtrusionFilter, 48 steps, the axis put on the body frame's y axis (the
//   bottom centred at the origin): a closed solid of revolution (walls
//   tapering from radius 60 at the bottom to 75 under the rim band, the band 100 wide). The
//   filter stores single-precision points: the mesh is exact to float rounding.
SurfaceMesh MakeTableMesh();
SurfaceMesh MakePotMesh();

}  // namespace wobble::pipelines
