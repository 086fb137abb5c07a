#include "pipelines/exports.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <stdexcept>
#include <vtkErrorCode.h>
#include <vtkImageData.h>
#include <vtkPolyData.h>
#include <vtkXMLImageDataWriter.h>
#include <vtkPointData.h>
#include <vtkDoubleArray.h>
#include <vtkXMLPolyDataWriter.h>

#include "wobble/dynamics/kinematics.h"
#include "wobble/formats/atomic_file.h"

namespace wobble::pipelines {
namespace {

// Runs a configured VTK writer on the temporary file; VTK reports failures through an error
// code rather than an exception.
template <class Writer> void RunWriter(Writer* writer, const std::string& tmp) {
  writer->SetFileName(tmp.c_str());
  writer->Write();
  const unsigned long code = writer->GetErrorCode();
  if (code != 0) throw std::runtime_error(std::string("VTK writer: ") + vtkErrorCode::GetStringFromErrorCode(code));
}

std::string XmlEscape(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '&') out += "&amp;";
    else if (c == '"') out += "&quot;";
    else if (c == '<') out += "&lt;";
    else if (c == '>') out += "&gt;";
    else out += c;
  }
  return out;
}

}  // namespace

std::string VtpBytes(vtkPolyData* data) {
  auto w = vtkSmartPointer<vtkXMLPolyDataWriter>::New();
  w->SetInputData(data);
  w->SetDataModeToAppended();
  w->EncodeAppendedDataOff();  // raw binary: smaller and faster than base64
  w->SetCompressorTypeToNone();
  w->WriteToOutputStringOn();
  w->Write();
  const unsigned long code = w->GetErrorCode();
  if (code != 0) throw std::runtime_error(std::string("VTK writer: ") + vtkErrorCode::GetStringFromErrorCode(code));
  return w->GetOutputString();
}

void WriteVtp(const std::string& path, vtkPolyData* data) { formats::WriteTextAtomically(path, VtpBytes(data)); }

void WriteVti(const std::string& path, vtkImageData* image) {
  formats::WriteFileAtomically(path, [&](const std::string& tmp) {
    auto w = vtkSmartPointer<vtkXMLImageDataWriter>::New();
    w->SetInputData(image);
    w->SetDataModeToAppended();
    w->EncodeAppendedDataOff();
    RunWriter(w.Get(), tmp);
  });
}

PngPixels PixelsOf(vtkImageData* image) {
  if (!image || image->GetScalarType() != VTK_UNSIGNED_CHAR)
    throw std::invalid_argument("a PNG needs an image of unsigned char pixels");
  int dims[3];
  image->GetDimensions(dims);
  PngPixels px;
  px.width = dims[0];
  px.height = dims[1];
  px.channels = image->GetNumberOfScalarComponents();
  if (px.channels < 1 || px.channels > 4) throw std::invalid_argument("a PNG needs 1 to 4 components per pixel");
  const size_t stride = size_t(px.width) * size_t(px.channels);
  px.bytes.resize(stride * size_t(std::max(0, px.height)));
  const auto* in = static_cast<const uint8_t*>(image->GetScalarPointer());
  for (int y = 0; y < px.height; ++y)  // VTK's rows start at the bottom
    std::copy_n(in + size_t(px.height - 1 - y) * stride, stride, px.bytes.data() + size_t(y) * stride);
  return px;
}

void WritePng(const std::string& path, vtkImageData* image, int compression) {
  WritePngPixels(path, PixelsOf(image), compression);
}

void PvdCollection::Add(double time, int part, const std::string& file, const std::string& name) {
  entries_.push_back({time, part, file, name});
}

void PvdCollection::Write(const std::string& pvd_path) const {
  namespace fs = std::filesystem;
  const fs::path folder = fs::path(pvd_path).parent_path();
  std::ostringstream xml;
  xml.precision(17);
  xml << "<?xml version=\"1.0\"?>\n"
      << "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <Collection>\n";
  for (const Entry& e : entries_) {
    std::string file = e.file;
    const fs::path rel = fs::path(e.file).lexically_relative(folder.empty() ? fs::path(".") : folder);
    if (!rel.empty() && rel.native().rfind("..", 0) != 0) file = rel.string();
    xml << "    <DataSet timestep=\"" << e.time << "\" group=\"\" part=\"" << e.part << "\"";
    if (!e.name.empty()) xml << " name=\"" << XmlEscape(e.name) << "\"";
    xml << " file=\"" << XmlEscape(file) << "\"/>\n";
  }
  xml << "  </Collection>\n</VTKFile>\n";
  formats::WriteTextAtomically(pvd_path, xml.str());
}

std::vector<ExrChannel> DisplacementImage(const World& world, int body_index, int width, int height) {
  if (width <= 0 || height <= 0) throw std::invalid_argument("displacement image size must be positive");
  const BodyModel& body = world.body<2>(body_index);
  const Lattice& lat = body.lattice();
  const VecQ<double>& q = world.q(body_index);
  const Frame<2, double> frame(q);
  // deformed control points in the world, W_ij = t + R (L_ij + Σ γ_d d^d_ij); the weights are
  // a partition of unity, so x(s, t) = Σ_ij W_ij B_i(s) B_j(t) is Eq. 4.2 with the rigid motion
  const int ns = lat.num_s(), nt = lat.num_t();
  std::vector<Eigen::Vector2d> W(lat.size());
  for (int c = 0; c < lat.size(); ++c) {
    Eigen::Vector2d l = body.rest_control()[c];
    for (int m = 0; m < body.num_modes(); ++m) l += body.modes()[m].displacement[c] * q[kRigidDofs + m];
    W[c] = WorldFromLocal(frame, Vec2<double>(l));
  }
  // the tensor-product weights separate: B_i(s) per column, B_j(t) per row
  const Basis1D basis_s(lat.basis(), ns), basis_t(lat.basis(), nt);
  std::vector<double> ws(size_t(width) * ns), wt(nt);
  for (int px = 0; px < width; ++px) basis_s.Weights((px + 0.5) / width, &ws[size_t(px) * ns]);
  std::vector<ExrChannel> channels = {{"disp.X", {}}, {"disp.Y", {}}};
  channels[0].data.resize(size_t(width) * height);
  channels[1].data.resize(size_t(width) * height);
  std::vector<Eigen::Vector2d> column(ns);
  for (int py = 0; py < height; ++py) {
    const double t = 1.0 - (py + 0.5) / height;
    basis_t.Weights(t, wt.data());
    for (int i = 0; i < ns; ++i) {
      column[i].setZero();
      for (int j = 0; j < nt; ++j) column[i] += wt[j] * W[lat.Index(i, j)];
    }
    for (int px = 0; px < width; ++px) {
      const double s = (px + 0.5) / width;
      Eigen::Vector2d x = Eigen::Vector2d::Zero();
      for (int i = 0; i < ns; ++i) x += ws[size_t(px) * ns + i] * column[i];
      const Eigen::Vector2d d = x - (lat.origin() + s * lat.axis_s() + t * lat.axis_t());
      channels[0].data[size_t(py) * width + px] = float(d.x());
      channels[1].data[size_t(py) * width + px] = float(d.y());
    }
  }
  return channels;
}

vtkSmartPointer<vtkImageData> DisplacementVolume(const World& world, int body_index, int nx, int ny, int nz) {
  if (nx <= 0 || ny <= 0 || nz <= 0) throw std::invalid_argument("displacement volume size must be positive");
  const BodyModelN<3>& body = world.body<3>(body_index);
  const LatticeN<3>& lat = body.lattice();
  const BodyState<3, double>& s = world.state<3>(body_index);
  // deformed control points in the world, W_c = t + R (L_c + Σ γ_d d^d_c): the weights are a
  // partition of unity, so x(s, t, u) = Σ_c W_c B_c(s, t, u) is Eq. 4.2 with the rigid motion
  std::vector<Eigen::Vector3d> W(size_t(lat.size()));
  for (int c = 0; c < lat.size(); ++c) {
    Eigen::Vector3d l = body.rest_control()[size_t(c)];
    for (int m = 0; m < body.num_modes(); ++m) l += body.modes()[size_t(m)].displacement[size_t(c)] * s.gamma()[m];
    W[size_t(c)] = s.translation() + s.orientation() * l;
  }
  const std::vector<Eigen::Vector3d> rest = lat.RestPoints();
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->SetDimensions(nx, ny, nz);
  const int n[3] = {nx, ny, nz};
  double spacing[3], direction[9];
  for (int a = 0; a < 3; ++a) {
    const Eigen::Vector3d axis = lat.axes()[size_t(a)];
    spacing[a] = axis.norm() / n[a];
    for (int r = 0; r < 3; ++r) direction[3 * r + a] = axis[r] / axis.norm();  // column a: the axis
  }
  image->SetSpacing(spacing);
  image->SetDirectionMatrix(direction);
  const Eigen::Vector3d first = lat.Evaluate(rest, Eigen::Vector3d(0.5 / nx, 0.5 / ny, 0.5 / nz));
  image->SetOrigin(first.data());
  auto disp = vtkSmartPointer<vtkDoubleArray>::New();
  disp->SetName("disp");
  disp->SetNumberOfComponents(3);
  disp->SetNumberOfTuples(vtkIdType(nx) * ny * nz);
  vtkIdType id = 0;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i, ++id) {
        const Eigen::Vector3d u((i + 0.5) / nx, (j + 0.5) / ny, (k + 0.5) / nz);
        const Eigen::Vector3d d = lat.Evaluate(W, u) - lat.Evaluate(rest, u);
        disp->SetTuple(id, d.data());
      }
  image->GetPointData()->AddArray(disp);
  image->GetPointData()->SetActiveVectors("disp");
  return image;
}

void WriteDisplacementExr(const std::string& path, const World& world, int body, int width, int height,
                          BackgroundWriter* writer) {
  // uncompressed: the displacements' float mantissas are noise to zlib, whose ZIP made the
  // demo's 256x85 image 5% smaller at 7.5 times the time (bench: BM_WriteDisplacementExr256x85)
  if (!writer)
    return WriteExrChannels(path, width, height, DisplacementImage(world, body, width, height), ExrCompression::kNone);
  writer->Submit([path, width, height, ch = DisplacementImage(world, body, width, height)] {
    WriteExrChannels(path, width, height, ch, ExrCompression::kNone);
  });
}

VtpSeriesWriter::VtpSeriesWriter(const World* world, std::string folder, std::string stem, std::vector<LinearDrawing> drawings,
                                 int shape_samples)
    : world_(world), folder_(std::move(folder)), stem_(std::move(stem)) {
  if (!world_) throw std::invalid_argument("VtpSeriesWriter needs a world");
  for (int b = 0; b < world_->num_bodies(); ++b) {
    const bool ffd = world_->kind(b) != BodyKind::kLinear;  // 2D or 3D: a lattice
    const std::string body = BodyLabel(*world_, b);
    auto lattice = vtkSmartPointer<LatticeSource>::New();
    auto points = vtkSmartPointer<MassPointSource>::New();
    auto shape = vtkSmartPointer<ShapeSource>::New();
    shape->SetSamplesPerSegment(shape_samples);
    if (!ffd && b < int(drawings.size())) shape->SetDrawing(drawings[b]);
    parts_.push_back({lattice, body + (ffd ? "_lattice" : "_box")});
    parts_.push_back({points, body + "_points"});
    parts_.push_back({shape, body + "_shape"});
  }
  for (Part& p : parts_) {
    p.source->SetWorld(world_);
    p.source->SetBody(int(&p - parts_.data()) / 3);
  }
  if (const std::shared_ptr<const Terrain>& t = world_->options().params.ground.terrain) {
    terrain_ = vtkSmartPointer<GroundSource>::New();
    terrain_->SetWorld(world_);
    FrameWholeTerrain(*t, terrain_);
  } else if (world_->options().params.ground_plane.enabled && world_->options().params.ground_plane.heightfield) {
    terrain_ = vtkSmartPointer<GroundSource>::New();  // the grid's triangles (GroundSource::DrawHeightfield)
    terrain_->SetWorld(world_);
  }
}

void VtpSeriesWriter::WriteFrame(int frame, BackgroundWriter* writer) {
  char number[32];
  std::snprintf(number, sizeof(number), "_%04d.vtp", frame);
  for (size_t p = 0; p < parts_.size(); ++p) {
    WorldSourceBase* source = parts_[p].source;
    source->Modified();
    source->Update();
    const std::string file = folder_ + "/" + parts_[p].name + number;
    if (writer) {
      // serialised here: VTK objects never reach the worker threads
      writer->Submit([file, bytes = VtpBytes(source->GetOutput())] { formats::WriteTextAtomically(file, bytes); });
    } else {
      WriteVtp(file, source->GetOutput());
    }
    pvd_.Add(world_->time(), int(p), file, parts_[p].name);
  }
  if (terrain_) {
    const std::string file = folder_ + "/terrain.vtp";
    if (!terrain_written_) {
      terrain_->Update();
      if (writer) writer->Submit([file, bytes = VtpBytes(terrain_->GetOutput())] { formats::WriteTextAtomically(file, bytes); });
      else WriteVtp(file, terrain_->GetOutput());
      terrain_written_ = true;
    }
    pvd_.Add(world_->time(), int(parts_.size()), file, "terrain");
  }
}

std::string VtpSeriesWriter::WriteCollection() const {
  pvd_.Write(CollectionPath());
  return CollectionPath();
}

}  // namespace wobble::pipelines
