// A rendered frame as a compositor wants it (the EXR frames of SceneView::WriteExr and the
// render driver): the characters' colour with an alpha that covers them alone, the rest of
// the picture (terrain or ground, springs, trails) as its own layer, the depth, and where each
// of the characters' pixels is on the next frame (the motion-vector layer, as Nuke's
// forward.u / forward.v, and as Blender's Vector pass, which also holds the motion to the
// previous frame). Which pixels the characters cover and how they move comes from
// their geometry as SceneView drew it (filled shapes and surfaces, outlines, lattices, mass
// points), projected to pixels and rasterised here on the CPU at pixel centres as OpenGL
// does, with a depth test, so that a pixel's motion is that of the surface in front. No VTK.
//
// Pixels: x to the right and y UP from the image's bottom-left corner (pixel (i, j) has its
// centre at (i + 0.5, j + 0.5)), as VTK's display coordinates and Nuke's motion vectors are;
// the layers returned have row 0 at the TOP, as EXR images do.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "pipelines/exr_io.h"

namespace wobble::pipelines {

// One frame's drawn characters. Vertices are grouped by the drawing that made them
// (`groups`: one per actor, its vertex count); a vertex keeps its index from frame to frame
// as long as its group's count does, which is what ties a point to itself on the next frame.
struct ScreenGeometry {
  std::vector<Eigen::Vector3d> vertices;  // x, y in pixels (y up), z the window depth in [0, 1]
  std::vector<double> w;                  // per vertex, the clip-space w (1 in a parallel view)
  std::vector<int> groups;                // vertex counts per drawing, in order
  std::vector<std::array<int, 3>> triangles;
  struct Segment {
    int a, b;
    double width;  // pixels, as drawn (the actor's line width)
  };
  std::vector<Segment> segments;
  struct Dot {
    int v;
    double size;  // pixels, the side of the square drawn
  };
  std::vector<Dot> dots;
};

// Per vertex, where it is on the next frame as homogeneous pixel coordinates (x w', y w', w'
// with w' its clip-space w then): linear in the point's 3D position, so interpolating them
// with a surface's perspective-correct weights and dividing gives exactly where any point of
// the surface goes under an affine motion, in perspective too. A vertex of a group whose
// vertex count changed (nothing ties it to the next frame), and every vertex when `next` is
// empty (the last frame), gets where it is now: no motion.
std::vector<Eigen::Vector3d> NextPixels(const ScreenGeometry& now, const ScreenGeometry& next);

struct CharacterLayers {
  std::vector<float> alpha;      // 1 where a character covers the pixel's centre, else 0
  std::vector<float> forward_u;  // the covering surface's motion to the next frame, pixels
  std::vector<float> forward_v;  // (0 where nothing covers the pixel)
  std::vector<float> backward_u;  // and to the previous frame (empty unless asked for)
  std::vector<float> backward_v;
};

// Rasterises `g` into a width x height image, sampling at pixel centres: triangles (with
// perspective-correct weights), segments as rectangles of their width along the line (no
// caps, as OpenGL's wide lines; every pixel of the width moves with the line's centre), dots
// as squares (moving with their vertex); the nearest primitive (smallest z) wins, ties to the
// later one. `next` is NextPixels(g, ...), and so is `previous` (null: no motion back).
// Primitives with a vertex that is not finite or behind the camera (w <= 0) are skipped.
CharacterLayers RasterizeCharacters(const ScreenGeometry& g, const std::vector<Eigen::Vector3d>& next, int width,
                                    int height, const std::vector<Eigen::Vector3d>* previous = nullptr);

// What the frame buffer held after a render, and the characters drawn: everything of an EXR
// frame but the motion, which needs the next frame's geometry (a render driver keeps a frame
// until the next is drawn). Rows of the images start at the TOP.
struct ExrFrame {
  int width = 0, height = 0;
  std::vector<uint8_t> srgb;   // the frame buffer's colour, 3 per pixel, 8-bit sRGB (ExrFrameChannels decodes it)
  std::vector<float> depth;    // distance from the camera along the view direction; +inf: nothing drawn
  std::vector<uint8_t> overlay;  // 1 where the 2D text overlay or colour bar was drawn (empty: none)
  ScreenGeometry characters;   // the bodies as drawn
  ExrMetadata metadata;        // the camera (and the frame's time, when in a series)
  bool terrain_layer = false;  // write the terrain.R/G/B/A layer (it costs a third of the file's time)
  bool nuke_motion = true;      // write forward.u/v
  bool blender_motion = false;  // write ViewLayer.Vector.X/Y/Z/W (four channels: a quarter more time)
};

// The frame's channels: R, G, B, A of the characters (linear-light colour premultiplied by A,
// A from the rasterised characters), with frame.terrain_layer terrain.R/G/B/A of everything
// else drawn (the ground or terrain, springs, trails, named points) where no character covers it,
// depth.Z of whatever is nearest;
// pixels of the 2D overlay are in no layer (its text hides what is under it, so a character
// under the text has a hole there: render without the overlay for compositing);
// and with frame.nuke_motion forward.u, forward.v: each character pixel's motion to the next
// frame in pixels (x right, y up; zero without a next frame), as Nuke reads it; with
// frame.blender_motion the same motions as Blender's Vector pass of a multilayer file,
// ViewLayer.Vector.X, .Y (the motion to the previous frame: zero without one) and .Z, .W
// (minus the motion to the next), as Cycles writes it. Colour, alpha and motion are half floats (motion to 2^-11 of its size: 0.03 px
// at 60 px), depth 32-bit floats.
std::vector<ExrChannel> ExrFrameChannels(const ExrFrame& frame, const ScreenGeometry* next,
                                         const ScreenGeometry* previous = nullptr);

// ExrFrameChannels written atomically to `path` (WriteExrChannels).
void WriteExrFrame(const std::string& path, const ExrFrame& frame, const ScreenGeometry* next,
                   const ScreenGeometry* previous, ExrCompression compression);

}  // namespace wobble::pipelines
