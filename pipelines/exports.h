// Files people open elsewhere, every one written atomically (wobble/formats/atomic_file.h):
//   .vtp  one vtkPolyData (VTK XML, raw appended binary), with its TimeValue field array
//   .pvd  a ParaView collection listing .vtp files per time step (and part): a time series
//   .vti  one vtkImageData (VTK XML)
//   .png  one RGB(A) vtkImageData (libpng, pipelines/png_io.h)
//   .exr  the deformation as a data image over the body's rest lattice (disp.X, disp.Y)
// Failures throw std::runtime_error naming the file and the reason; an earlier file of the
// same name is left as it was.
#pragma once

#include <string>
#include <vector>
#include <vtkSmartPointer.h>

#include "pipelines/background_writer.h"
#include "pipelines/exr_io.h"
#include "pipelines/png_io.h"
#include "pipelines/world_sources.h"

class vtkImageData;
class vtkPolyData;

namespace wobble::pipelines {

void WriteVtp(const std::string& path, vtkPolyData* data);
// The .vtp file's bytes: WriteVtp is formats::WriteTextAtomically(path, VtpBytes(data)), split
// so that the VTK part runs on the caller's thread and only the file write on a BackgroundWriter.
std::string VtpBytes(vtkPolyData* data);
void WriteVti(const std::string& path, vtkImageData* image);
// compression: zlib level 0 (none, fastest) to 9 (smallest); PNG is lossless at every level.
void WritePng(const std::string& path, vtkImageData* image, int compression = 5);
// An unsigned-char VTK image as PNG pixels (rows flipped to start at the top).
PngPixels PixelsOf(vtkImageData* image);

// A ParaView .pvd collection: <DataSet timestep=".." part=".." file=".."/> per entry; file
// names are written relative to the .pvd's folder when they lie under it.
class PvdCollection {
 public:
  void Add(double time, int part, const std::string& file, const std::string& name = "");
  void Write(const std::string& pvd_path) const;
  int size() const { return int(entries_.size()); }

 private:
  struct Entry {
    double time;
    int part;
    std::string file, name;
  };
  std::vector<Entry> entries_;
};

// The deformation of body `body` over its rest lattice domain as a width × height image:
// pixel (px, py) (py from the top) stands for lattice coordinates
// s = (px + ½)/width, t = 1 − (py + ½)/height, i.e. the rest point p = origin + s·axis_s + t·axis_t,
// and holds disp = x(s, t) − p: where that point of the rest drawing is now in the world
// (Eq. 4.2, rigid motion included) minus where it was drawn. Channels disp.X, disp.Y.
std::vector<ExrChannel> DisplacementImage(const World& world, int body, int width, int height);
// The same for a 3D FFD body: its rest lattice box as an nx × ny × nz image (vtkImageData
// with the lattice's origin, spacing and axes as its direction), voxel (i, j, k) standing for
// lattice coordinates ((i + ½)/nx, (j + ½)/ny, (k + ½)/nz); point array "disp" (3 components)
// = x(s, t, u) − p, the point's world position (Eq. 4.2 with the rigid motion) minus its rest
// position. For ParaView (.vti).
vtkSmartPointer<vtkImageData> DisplacementVolume(const World& world, int body, int nx, int ny, int nz);
// With a BackgroundWriter the image is computed now and written by its thread.
void WriteDisplacementExr(const std::string& path, const World& world, int body, int width, int height,
                          BackgroundWriter* writer = nullptr);

// Writes every body of a world per frame as three .vtp files, <folder>/<body>_<part>_NNNN.vtp
// with <body> the body's name ("body<b>" when it has none) and <part> lattice (FFD bodies) or
// box (linear bodies: the control box), points and shape, and keeps <folder>/<stem>.pvd
// listing them as parts 3b, 3b+1, 3b+2 of each time step (rewritten by WriteCollection()).
// Linear bodies are drawn with drawings[b] (none: an empty shape); FFD bodies with their own
// drawing resampled shape_samples times per segment.
class VtpSeriesWriter {
 public:
  VtpSeriesWriter(const World* world, std::string folder, std::string stem, std::vector<LinearDrawing> drawings = {},
                  int shape_samples = 16);
  // Writes the current state as frame number `frame` (the file names' NNNN) at the world's
  // time; with a BackgroundWriter the polydata are copied now and written by its thread.
  void WriteFrame(int frame, BackgroundWriter* writer = nullptr);
  // Writes the .pvd; returns its path.
  std::string WriteCollection() const;
  std::string CollectionPath() const { return folder_ + "/" + stem_ + ".pvd"; }

 private:
  struct Part {
    vtkSmartPointer<WorldSourceBase> source;
    std::string name;  // <body>_<part>
  };
  const World* world_;
  std::string folder_, stem_;
  std::vector<Part> parts_;  // 3 per body, in part order
  // A 2D world's terrain or a 3D one's heightfield: the last part, one file (it does not move)
  // listed at every time
  vtkSmartPointer<GroundSource> terrain_;
  bool terrain_written_ = false;
  PvdCollection pvd_;
};

}  // namespace wobble::pipelines
