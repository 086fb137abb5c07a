#include "pipelines/exr_frame.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace wobble::pipelines {
namespace {

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
  Raster(const ScreenGeometry& g, const std::vector<Eigen::Vector3d>& next, int width, int height)
      : g_(g), next_(next), now_(NextPixels(g, ScreenGeometry())), width_(width), height_(height),
        depth_(size_t(width) * height, std::numeric_limits<double>::infinity()) {
    out_.alpha.assign(size_t(width) * height, 0.0f);
    out_.forward_u.assign(size_t(width) * height, 0.0f);
    out_.forward_v.assign(size_t(width) * height, 0.0f);
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
        // where the surface point is now and on the next frame, both interpolated alike (so
        // that a still surface gives exactly 0; now is the pixel's centre up to rounding)
        const Eigen::Vector3d h = pa * next_[size_t(t[0])] + pb * next_[size_t(t[1])] + pc * next_[size_t(t[2])];
        const Eigen::Vector3d h0 = pa * now_[size_t(t[0])] + pb * now_[size_t(t[1])] + pc * now_[size_t(t[2])];
        Write(x, y, z, h.head<2>() / h.z() - h0.head<2>() / h0.z());
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
        const Eigen::Vector3d h = (1 - u) * next_[size_t(s.a)] + u * next_[size_t(s.b)];
        const Eigen::Vector3d h0 = (1 - u) * now_[size_t(s.a)] + u * now_[size_t(s.b)];
        Write(x, y, (1 - t) * a.z() + t * b.z(), h.head<2>() / h.z() - h0.head<2>() / h0.z());
      }
  }

  void Dot(const ScreenGeometry::Dot& d) {
    if (!Usable(d.v)) return;
    const Eigen::Vector3d& c = g_.vertices[size_t(d.v)];
    const Eigen::Vector3d& h = next_[size_t(d.v)];
    const Eigen::Vector2d motion = h.head<2>() / h.z() - now_[size_t(d.v)].head<2>() / now_[size_t(d.v)].z();  // with its vertex
    const double half = 0.5 * d.size;
    int x0, x1, y0, y1;
    if (!PixelRange(c.x() - half, c.x() + half, width_, &x0, &x1) || !PixelRange(c.y() - half, c.y() + half, height_, &y0, &y1))
      return;
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) Write(x, y, c.z(), motion);
  }

  CharacterLayers Take() { return std::move(out_); }

 private:
  void Write(int x, int y, double z, const Eigen::Vector2d& m) {
    const size_t at = size_t(height_ - 1 - y) * width_ + x;  // row 0 at the top
    if (z > depth_[at] || !std::isfinite(z)) return;
    depth_[at] = z;
    out_.alpha[at] = 1.0f;
    out_.forward_u[at] = std::isfinite(m.x()) ? float(m.x()) : 0.0f;  // a next position behind the camera
    out_.forward_v[at] = std::isfinite(m.y()) ? float(m.y()) : 0.0f;
  }

  const ScreenGeometry& g_;
  const std::vector<Eigen::Vector3d>& next_;
  const std::vector<Eigen::Vector3d> now_;  // the vertices now, homogeneous as next_
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
                                    int height) {
  if (g.w.size() != g.vertices.size() || next.size() != g.vertices.size() || width < 1 || height < 1)
    throw std::invalid_argument("RasterizeCharacters: a w and a next position per vertex, and a size of at least one pixel");
  Raster r(g, next, width, height);
  for (const std::array<int, 3>& t : g.triangles) r.Triangle(t);
  for (const ScreenGeometry::Segment& s : g.segments) r.Segment(s);
  for (const ScreenGeometry::Dot& d : g.dots) r.Dot(d);
  return r.Take();
}

std::vector<ExrChannel> ExrFrameChannels(const ExrFrame& frame, const ScreenGeometry* next) {
  const size_t n = size_t(frame.width) * size_t(frame.height);
  if (frame.rgb.size() != 3 * n || frame.depth.size() != n || (!frame.overlay.empty() && frame.overlay.size() != n))
    throw std::invalid_argument("ExrFrameChannels: an image of another size");
  CharacterLayers c = RasterizeCharacters(frame.characters, NextPixels(frame.characters, next ? *next : ScreenGeometry()),
                                          frame.width, frame.height);
  // the characters' R, G, B, A, and terrain.R, G, B, A of the rest only when asked for
  std::vector<ExrChannel> ch = {{"R", {}, true}, {"G", {}, true}, {"B", {}, true}, {"A", {}, true}};
  if (frame.terrain_layer)
    for (const char* name : {"terrain.R", "terrain.G", "terrain.B", "terrain.A"}) ch.push_back({name, {}, true});
  for (ExrChannel& x : ch) x.data.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const float a = frame.overlay.empty() || !frame.overlay[i] ? c.alpha[i] : 0.0f;
    for (int k = 0; k < 3; ++k) ch[size_t(k)].data[i] = a * frame.rgb[3 * i + size_t(k)];
    ch[3].data[i] = a;
    if (a == 0.0f) c.forward_u[i] = c.forward_v[i] = 0.0f;  // under the overlay
    if (frame.terrain_layer) {
      const float rest = std::isinf(frame.depth[i]) ? 0.0f : 1.0f - a;  // drawn, and not a character
      for (int k = 0; k < 3; ++k) ch[size_t(4 + k)].data[i] = rest * frame.rgb[3 * i + size_t(k)];
      ch[7].data[i] = rest;
    }
  }
  ch.push_back({"depth.Z", frame.depth});
  ch.push_back({"forward.u", std::move(c.forward_u), true});
  ch.push_back({"forward.v", std::move(c.forward_v), true});
  return ch;
}

void WriteExrFrame(const std::string& path, const ExrFrame& frame, const ScreenGeometry* next, ExrCompression compression) {
  WriteExrChannels(path, frame.width, frame.height, ExrFrameChannels(frame, next), compression, frame.metadata);
}

}  // namespace wobble::pipelines
