#include "pipelines/exr_frame.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace wobble::pipelines {
namespace {

// 8-bit sRGB-encoded values (IEC 61966-2-1) decoded to linear light.
const std::array<float, 256>& LinearOfSrgb() {
  static const std::array<float, 256> linear = [] {
    std::array<float, 256> lut;
    for (int v = 0; v < 256; ++v) {
      const double c = v / 255.0;
      lut[size_t(v)] = float(c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4));
    }
    return lut;
  }();
  return linear;
}

// The pixels whose centres may lie in [lo, hi] along one axis of an image n pixels wide.
bool PixelRange(double lo, double hi, int n, int* first, int* last) {
  if (!(lo <= hi)) return false;
  const double a = std::max(std::ceil(lo - 0.5), 0.0), b = std::min(std::floor(hi - 0.5), double(n - 1));
  if (a > b) return false;
  *first = int(a);
  *last = int(b);
  return true;
}

class Raster {
 public:
  Raster(const ScreenGeometry& g, const std::vector<Eigen::Vector3d>& next, const std::vector<Eigen::Vector3d>* previous,
         int width, int height)
      : g_(g), next_(next), now_(NextPixels(g, ScreenGeometry())), previous_(previous ? *previous : now_),
        backward_(previous != nullptr), width_(width), height_(height),
        depth_(size_t(width) * height, std::numeric_limits<double>::infinity()) {
    for (std::vector<float>* layer : {&out_.alpha, &out_.forward_u, &out_.forward_v})
      layer->assign(size_t(width) * height, 0.0f);
    if (backward_)
      for (std::vector<float>* layer : {&out_.backward_u, &out_.backward_v}) layer->assign(size_t(width) * height, 0.0f);
  }

  // The motion to the previous frame, when asked for (at: a point's position on a frame).
  template <class At> Eigen::Vector2d Back(const At& at, const Eigen::Vector2d& here) const {
    return backward_ ? Eigen::Vector2d(at(previous_) - here) : Eigen::Vector2d::Zero();
  }

  bool Usable(int v) const { return g_.vertices[size_t(v)].allFinite() && g_.w[size_t(v)] > 0; }

  void Triangle(const std::array<int, 3>& t) {
    for (int v : t)
      if (!Usable(v)) return;
    const Eigen::Vector3d &a = g_.vertices[size_t(t[0])], &b = g_.vertices[size_t(t[1])], &c = g_.vertices[size_t(t[2])];
    const double area = (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
    if (area == 0 || !std::isfinite(area)) return;
    int x0, x1, y0, y1;
    if (!PixelRange(std::min({a.x(), b.x(), c.x()}), std::max({a.x(), b.x(), c.x()}), width_, &x0, &x1) ||
        !PixelRange(std::min({a.y(), b.y(), c.y()}), std::max({a.y(), b.y(), c.y()}), height_, &y0, &y1))
      return;
    // perspective-correct weights: screen weights over w, renormalised
    const double iw[3] = {1.0 / g_.w[size_t(t[0])], 1.0 / g_.w[size_t(t[1])], 1.0 / g_.w[size_t(t[2])]};
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const double px = x + 0.5, py = y + 0.5;  // the pixel's centre: where the surface point is now
        // screen barycentric weights of a, b, c (edge functions over the signed area)
        const double la = ((b.x() - px) * (c.y() - py) - (b.y() - py) * (c.x() - px)) / area;
        const double lb = ((c.x() - px) * (a.y() - py) - (c.y() - py) * (a.x() - px)) / area;
        const double lc = 1.0 - la - lb;
        if (la < 0 || lb < 0 || lc < 0) continue;
        const double z = la * a.z() + lb * b.z() + lc * c.z();  // window depth is linear on screen
        double pa = la * iw[0], pb = lb * iw[1], pc = lc * iw[2];
        const double sum = pa + pb + pc;
        pa /= sum;
        pb /= sum;
        pc /= sum;
        // where the surface point is now and on the next and previous frames, all interpolated
        // alike (so that a still surface gives exactly 0; now is the pixel's centre up to rounding)
        auto at = [&](const std::vector<Eigen::Vector3d>& h) {
          const Eigen::Vector3d p = pa * h[size_t(t[0])] + pb * h[size_t(t[1])] + pc * h[size_t(t[2])];
          return Eigen::Vector2d(p.head<2>() / p.z());
        };
        const Eigen::Vector2d here = at(now_);
        Write(x, y, z, at(next_) - here, Back(at, here));
      }
  }

  void Segment(const ScreenGeometry::Segment& s) {
    if (!Usable(s.a) || !Usable(s.b)) return;
    const Eigen::Vector3d &a = g_.vertices[size_t(s.a)], &b = g_.vertices[size_t(s.b)];
    const Eigen::Vector2d d = (b - a).head<2>();
    const double len2 = d.squaredNorm(), half = 0.5 * s.width;
    if (len2 == 0 || !std::isfinite(len2)) return;
    int x0, x1, y0, y1;
    if (!PixelRange(std::min(a.x(), b.x()) - half, std::max(a.x(), b.x()) + half, width_, &x0, &x1) ||
        !PixelRange(std::min(a.y(), b.y()) - half, std::max(a.y(), b.y()) + half, height_, &y0, &y1))
      return;
    const double len = std::sqrt(len2);
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const Eigen::Vector2d p(x + 0.5 - a.x(), y + 0.5 - a.y());
        const double t = p.dot(d) / len2;
        const double across = (d.x() * p.y() - d.y() * p.x()) / len;
        if (t < 0 || t > 1 || std::abs(across) > half) continue;
        // the point of the line's centre at t, now and (perspective-correct) on the next frame
        const double ta = (1 - t) / g_.w[size_t(s.a)], tb = t / g_.w[size_t(s.b)];
        const double u = tb / (ta + tb);
        auto at = [&](const std::vector<Eigen::Vector3d>& h) {
          const Eigen::Vector3d p = (1 - u) * h[size_t(s.a)] + u * h[size_t(s.b)];
          return Eigen::Vector2d(p.head<2>() / p.z());
        };
        const Eigen::Vector2d here = at(now_);
        Write(x, y, (1 - t) * a.z() + t * b.z(), at(next_) - here, Back(at, here));
      }
  }

  void Dot(const ScreenGeometry::Dot& d) {
    if (!Usable(d.v)) return;
    const Eigen::Vector3d& c = g_.vertices[size_t(d.v)];
    auto at = [&](const std::vector<Eigen::Vector3d>& h) {
      return Eigen::Vector2d(h[size_t(d.v)].head<2>() / h[size_t(d.v)].z());
    };
    const Eigen::Vector2d here = at(now_), motion = at(next_) - here, back = Back(at, here);  // with its vertex
    const double half = 0.5 * d.size;
    int x0, x1, y0, y1;
    if (!PixelRange(c.x() - half, c.x() + half, width_, &x0, &x1) || !PixelRange(c.y() - half, c.y() + half, height_, &y0, &y1))
      return;
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) Write(x, y, c.z(), motion, back);
  }

  CharacterLayers Take() { return std::move(out_); }

 private:
  void Write(int x, int y, double z, const Eigen::Vector2d& forward, const Eigen::Vector2d& backward) {
    const size_t at = size_t(height_ - 1 - y) * width_ + x;  // row 0 at the top
    if (z > depth_[at] || !std::isfinite(z)) return;
    depth_[at] = z;
    out_.alpha[at] = 1.0f;
    auto finite = [](double m) { return std::isfinite(m) ? float(m) : 0.0f; };  // a position behind the camera
    out_.forward_u[at] = finite(forward.x());
    out_.forward_v[at] = finite(forward.y());
    if (!backward_) return;
    out_.backward_u[at] = finite(backward.x());
    out_.backward_v[at] = finite(backward.y());
  }

  const ScreenGeometry& g_;
  const std::vector<Eigen::Vector3d>& next_;
  const std::vector<Eigen::Vector3d> now_;  // the vertices now, homogeneous as next_
  const std::vector<Eigen::Vector3d>& previous_;
  const bool backward_;  // the motion to the previous frame is asked for
  const int width_, height_;
  std::vector<double> depth_;
  CharacterLayers out_;
};

}  // namespace

std::vector<Eigen::Vector3d> NextPixels(const ScreenGeometry& now, const ScreenGeometry& next) {
  auto homogeneous = [](const ScreenGeometry& g, size_t i) {
    return Eigen::Vector3d(g.vertices[i].x() * g.w[i], g.vertices[i].y() * g.w[i], g.w[i]);
  };
  std::vector<Eigen::Vector3d> h(now.vertices.size());
  for (size_t i = 0; i < h.size(); ++i) h[i] = homogeneous(now, i);
  if (next.w.size() != next.vertices.size()) return h;
  size_t a = 0, b = 0;  // the first vertex of the group in now and in next
  for (size_t k = 0; k < now.groups.size(); ++k) {
    const int n = now.groups[k];
    if (k < next.groups.size() && next.groups[k] == n)
      for (int i = 0; i < n; ++i) {
        const Eigen::Vector3d there = homogeneous(next, b + size_t(i));
        if (there.allFinite() && there.z() > 0) h[a + size_t(i)] = there;
      }
    a += size_t(n);
    if (k < next.groups.size()) b += size_t(next.groups[k]);
  }
  return h;
}

CharacterLayers RasterizeCharacters(const ScreenGeometry& g, const std::vector<Eigen::Vector3d>& next, int width,
                                    int height, const std::vector<Eigen::Vector3d>* previous) {
  if (g.w.size() != g.vertices.size() || next.size() != g.vertices.size() || width < 1 || height < 1 ||
      (previous && previous->size() != g.vertices.size()))
    throw std::invalid_argument(
        "RasterizeCharacters: a w, a next (and a previous) position per vertex, and a size of at least one pixel");
  Raster r(g, next, previous, width, height);
  for (const std::array<int, 3>& t : g.triangles) r.Triangle(t);
  for (const ScreenGeometry::Segment& s : g.segments) r.Segment(s);
  for (const ScreenGeometry::Dot& d : g.dots) r.Dot(d);
  return r.Take();
}

std::vector<ExrChannel> ExrFrameChannels(const ExrFrame& frame, const ScreenGeometry* next,
                                         const ScreenGeometry* previous) {
  const size_t n = size_t(frame.width) * size_t(frame.height);
  if (frame.srgb.size() != 3 * n || frame.depth.size() != n || (!frame.overlay.empty() && frame.overlay.size() != n))
    throw std::invalid_argument("ExrFrameChannels: an image of another size");
  const std::vector<Eigen::Vector3d> before =
      frame.blender_motion ? NextPixels(frame.characters, previous ? *previous : ScreenGeometry())
                           : std::vector<Eigen::Vector3d>();
  CharacterLayers c = RasterizeCharacters(frame.characters, NextPixels(frame.characters, next ? *next : ScreenGeometry()),
                                          frame.width, frame.height, frame.blender_motion ? &before : nullptr);
  // the characters' R, G, B, A, and terrain.R, G, B, A of the rest only when asked for
  std::vector<ExrChannel> ch = {{"R", {}, true}, {"G", {}, true}, {"B", {}, true}, {"A", {}, true}};
  if (frame.terrain_layer)
    for (const char* name : {"terrain.R", "terrain.G", "terrain.B", "terrain.A"}) ch.push_back({name, {}, true});
  for (ExrChannel& x : ch) x.data.resize(n);
  const std::array<float, 256>& linear = LinearOfSrgb();
  for (size_t i = 0; i < n; ++i) {
    const float a = frame.overlay.empty() || !frame.overlay[i] ? c.alpha[i] : 0.0f;
    for (int k = 0; k < 3; ++k) ch[size_t(k)].data[i] = a * linear[frame.srgb[3 * i + size_t(k)]];
    ch[3].data[i] = a;
    if (a == 0.0f) {  // under the overlay
      c.forward_u[i] = c.forward_v[i] = 0.0f;
      if (frame.blender_motion) c.backward_u[i] = c.backward_v[i] = 0.0f;
    }
    if (frame.terrain_layer) {
      const float rest = std::isinf(frame.depth[i]) ? 0.0f : 1.0f - a;  // drawn, and not a character
      for (int k = 0; k < 3; ++k) ch[size_t(4 + k)].data[i] = rest * linear[frame.srgb[3 * i + size_t(k)]];
      ch[7].data[i] = rest;
    }
  }
  ch.push_back({"depth.Z", frame.depth});
  if (frame.blender_motion) {
    // Blender's Vector pass, as Cycles fills it: X, Y the motion to the previous frame and Z, W
    // minus the motion to the next (both pixels, y up)
    std::vector<float> minus_u(n), minus_v(n);
    for (size_t i = 0; i < n; ++i) {
      minus_u[i] = -c.forward_u[i];
      minus_v[i] = -c.forward_v[i];
    }
    ch.push_back({"ViewLayer.Vector.X", std::move(c.backward_u), true});
    ch.push_back({"ViewLayer.Vector.Y", std::move(c.backward_v), true});
    ch.push_back({"ViewLayer.Vector.Z", std::move(minus_u), true});
    ch.push_back({"ViewLayer.Vector.W", std::move(minus_v), true});
  }
  if (frame.nuke_motion) {
    ch.push_back({"forward.u", std::move(c.forward_u), true});
    ch.push_back({"forward.v", std::move(c.forward_v), true});
  }
  return ch;
}

void WriteExrFrame(const std::string& path, const ExrFrame& frame, const ScreenGeometry* next,
                   const ScreenGeometry* previous, ExrCompression compression) {
  WriteExrChannels(path, frame.width, frame.height, ExrFrameChannels(frame, next, previous), compression, frame.metadata);
}

}  // namespace wobble::pipelines
