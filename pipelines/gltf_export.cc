#include "pipelines/gltf_export.h"

#include <tiny_gltf.h>
#include <vtkCellArray.h>
#include <vtkContourTriangulator.h>
#include <vtkIdList.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkTriangleFilter.h>

#include <algorithm>
#include <cmath>
#include <tuple>
#include <cstring>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "pipelines/world_sources.h"
#include "wobble/dynamics/kinematics.h"
#include "wobble/formats/atomic_file.h"

namespace wobble::pipelines {
namespace {

// Builds the model's one buffer: each Add* appends a float or uint32 array (4-byte aligned, as
// glTF wants for both) as its own bufferView and accessor and returns the accessor's index.
class BufferBuilder {
 public:
  explicit BufferBuilder(tinygltf::Model* model) : model_(model) { model_->buffers.emplace_back(); }

  // `values.size() / components` elements of `components` floats (type TINYGLTF_TYPE_*);
  // with_bounds: min and max per component, which glTF requires of POSITION (targets' too)
  // and of animation inputs.
  // vertices: vertex data (the bufferView's target ARRAY_BUFFER), else animation data.
  int AddFloats(const std::vector<float>& values, int components, int type, bool with_bounds, bool vertices = false) {
    const size_t count = values.size() / size_t(components);
    tinygltf::Accessor a;
    a.bufferView = AddView(values.data(), values.size() * sizeof(float), vertices ? TINYGLTF_TARGET_ARRAY_BUFFER : 0);
    a.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
    a.count = count;
    a.type = type;
    if (with_bounds && count > 0) {
      a.minValues.assign(size_t(components), std::numeric_limits<double>::infinity());
      a.maxValues.assign(size_t(components), -std::numeric_limits<double>::infinity());
      for (size_t i = 0; i < values.size(); ++i) {
        const size_t c = i % size_t(components);
        a.minValues[c] = std::min(a.minValues[c], double(values[i]));
        a.maxValues[c] = std::max(a.maxValues[c], double(values[i]));
      }
    }
    model_->accessors.push_back(std::move(a));
    return int(model_->accessors.size()) - 1;
  }
  int AddIndices(const std::vector<unsigned>& indices) {
    tinygltf::Accessor a;
    a.bufferView = AddView(indices.data(), indices.size() * sizeof(unsigned), TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
    a.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
    a.count = indices.size();
    a.type = TINYGLTF_TYPE_SCALAR;
    model_->accessors.push_back(std::move(a));
    return int(model_->accessors.size()) - 1;
  }

 private:
  int AddView(const void* data, size_t bytes, int target = 0) {
    std::vector<unsigned char>& buffer = model_->buffers[0].data;
    tinygltf::BufferView v;
    v.buffer = 0;
    v.byteOffset = buffer.size();  // every array is of 4-byte elements: offsets stay aligned
    v.byteLength = bytes;
    v.target = target;
    buffer.resize(buffer.size() + bytes);
    if (bytes > 0) std::memcpy(buffer.data() + v.byteOffset, data, bytes);
    model_->bufferViews.push_back(std::move(v));
    return int(model_->bufferViews.size()) - 1;
  }
  tinygltf::Model* model_;
};

void Append3(std::vector<float>* out, const Eigen::Vector3d& v) {
  for (int i = 0; i < 3; ++i) out->push_back(float(v[i]));
}

// The closed polylines of a 2D drawing filled (the clean style's fill): each polygon of
// `samples` (rest positions, in order from `first`) triangulated by VTK's contour
// triangulator, which takes concave outlines.
void FillClosedOutlines(const std::vector<Eigen::Vector2d>& rest, const std::vector<std::pair<int, bool>>& polylines,
                        unsigned first, std::vector<unsigned>* triangles) {
  auto points = vtkSmartPointer<vtkPoints>::New();
  points->SetDataTypeToDouble();
  for (const Eigen::Vector2d& p : rest) points->InsertNextPoint(p.x(), p.y(), 0.0);
  int start = 0;
  for (const auto& [count, closed] : polylines) {
    if (closed && count >= 3) {
      auto polygon = vtkSmartPointer<vtkIdList>::New();
      for (int k = 0; k < count; ++k) polygon->InsertNextId(start + k);
      auto cells = vtkSmartPointer<vtkCellArray>::New();
      vtkContourTriangulator::TriangulatePolygon(polygon, points, cells);  // 0: partly filled, still drawn
      auto cell = vtkSmartPointer<vtkIdList>::New();
      for (cells->InitTraversal(); cells->GetNextCell(cell);)
        if (cell->GetNumberOfIds() == 3)
          for (int i = 0; i < 3; ++i) triangles->push_back(first + unsigned(cell->GetId(i)));
    }
    start += count;
  }
}

// The segments of polylines of `count` samples each, from vertex `first` on (closed: back to the start).
void AddPolylines(const std::vector<std::pair<int, bool>>& polylines, unsigned first, std::vector<unsigned>* lines) {
  for (const auto& [count, closed] : polylines) {
    for (int k = 0; k + 1 < count; ++k) lines->insert(lines->end(), {first + unsigned(k), first + unsigned(k + 1)});
    if (closed && count > 2) lines->insert(lines->end(), {first + unsigned(count - 1), first});
    first += unsigned(count);
  }
}

}  // namespace

GltfRecorder::GltfRecorder(const World* world, const std::vector<LinearDrawing>& drawings, int shape_samples)
    : world_(world), shape_samples_(shape_samples) {
  for (int b = 0; b < world->num_bodies(); ++b) {
    if (world->IsFfd(b, 3)) parts_.push_back(FfdPart<3>(b));
    else if (world->IsFfd(b, 2)) parts_.push_back(FfdPart<2>(b));
    else if (b < int(drawings.size()) && drawings[size_t(b)].dim() != 0) parts_.push_back(LinearPart(b, drawings[size_t(b)]));
    else skipped_.push_back(world->body_name(b));  // a linear body is seen only through a drawing
    if (!parts_.empty() && parts_.back().body == b && parts_.back().triangles.empty() && parts_.back().lines.empty()) {
      parts_.pop_back();  // nothing to draw (an FFD body without mesh or drawing)
      skipped_.push_back(world->body_name(b));
    }
  }
}

int GltfRecorder::num_bodies() const {
  return int(std::count_if(parts_.begin(), parts_.end(), [](const Part& p) { return p.body >= 0; }));
}

// An FFD body: its mesh's vertices and then its drawing's samples, each with the b0 and B that
// ShapeSource moves it with (world_sources.cc): the mesh's from the body (mesh_rest_local),
// the samples' from BodyModelN::LocalBasis (MakeDrawingSamples).
template <int Dim> GltfRecorder::Part GltfRecorder::FfdPart(int b) const {
  const BodyModelN<Dim>& model = world_->body<Dim>(b);
  Part part;
  part.motion = Part::Motion::kFfd;
  part.body = b;
  part.name = BodyLabel(*world_, b);  // as the .vtp series names it
  const int modes = model.num_modes();
  part.targets.resize(size_t(modes));
  auto add = [&](const Eigen::Matrix<double, Dim, 1>& b0, const auto& B) {
    Append3(&part.rest, To3(b0));
    for (int d = 0; d < modes; ++d) Append3(&part.targets[size_t(d)], To3(Eigen::Matrix<double, Dim, 1>(B.col(d))));
  };
  const TriangleMeshN<Dim>& mesh = model.def().mesh;
  for (int v = 0; v < int(mesh.points.size()); ++v) add(model.mesh_rest_local(v), model.mesh_mode_matrix(v));
  for (const std::array<int, 3>& t : mesh.triangles)
    for (int i : t) part.triangles.push_back(unsigned(i));
  const DrawingSamples<Dim> samples = MakeDrawingSamples(model, shape_samples_);
  const unsigned first = unsigned(mesh.points.size());
  for (size_t k = 0; k < samples.st.size(); ++k) add(samples.b0[k], samples.B[k]);
  AddPolylines(samples.polylines, first, &part.lines);
  if constexpr (Dim == 2) FillClosedOutlines(samples.b0, samples.polylines, first, &part.triangles);
  for (int d = 0; d < modes; ++d) {
    const std::string& name = model.modes()[size_t(d)].name;
    part.target_names.push_back(name.empty() ? "mode_" + std::to_string(d + 1) : name);
  }
  return part;
}

// A linear body: x = R p(u) = Σ_ij R_ij p_j(u) e_i, so the base is 0 and target (i, j) holds
// p_j(u) e_i at every vertex; the weights are R's entries (row by row).
GltfRecorder::Part GltfRecorder::LinearPart(int b, const LinearDrawing& drawing) const {
  const LinearBodyModel& model = world_->linear_model(b);
  Part part;
  part.motion = Part::Motion::kLinear;
  part.body = b;
  part.name = BodyLabel(*world_, b);  // as the .vtp series names it
  const int d = model.dim(), n = model.basis_size();
  part.targets.resize(size_t(d * n));
  for (int i = 0; i < d; ++i)
    for (int j = 0; j < n; ++j) part.target_names.push_back("R_" + std::to_string(i) + "_" + std::to_string(j));
  auto add = [&](const Eigen::VectorXd& u) {
    const Eigen::VectorXd p = model.Basis(u);
    for (int k = 0; k < 3; ++k) part.rest.push_back(0.0f);
    for (int i = 0; i < d; ++i)
      for (int j = 0; j < n; ++j) {
        std::vector<float>& target = part.targets[size_t(i * n + j)];
        for (int k = 0; k < 3; ++k) target.push_back(k == i ? float(p[j]) : 0.0f);
      }
  };
  std::vector<std::pair<int, bool>> polylines;
  for (const LinearDrawing::Polyline& line : drawing.polylines) {
    for (const Eigen::VectorXd& u : line.points) add(u);
    polylines.push_back({int(line.points.size()), line.closed});
  }
  AddPolylines(polylines, 0, &part.lines);
  const unsigned first = unsigned(part.rest.size() / 3);
  for (const Eigen::VectorXd& u : drawing.vertices) add(u);
  for (const auto& t : drawing.triangles)
    for (int i : t) part.triangles.push_back(first + unsigned(i));
  return part;
}

// The ground as GroundSource draws it now, under the bodies standing on it, triangulated.
void GltfRecorder::AddGround() {
  bool stands = false;
  Eigen::AlignedBox3d bodies;
  for (int b = 0; b < world_->num_bodies(); ++b) {
    if (GroundDimensionOf(*world_, b) == 0) continue;
    stands = true;
    bodies.extend(world_->kind(b) == BodyKind::kFfd ? FfdBodyBounds(*world_, b) : LinearBodyBounds(*world_, b));
  }
  if (!stands) return;
  auto ground = vtkSmartPointer<GroundSource>::New();
  ground->SetWorld(world_);
  if (const std::shared_ptr<const Terrain>& terrain = world_->options().params.ground.terrain) {
    FrameWholeTerrain(*terrain, ground);
  } else {  // a line's band or the plane's square under the bodies, wide enough for their travel
    ground->SetCenter(bodies.center().x(), bodies.center().y());
    ground->SetLength(std::max(2000.0, 20.0 * bodies.diagonal().norm()));
  }
  auto triangles = vtkSmartPointer<vtkTriangleFilter>::New();
  triangles->SetInputConnection(ground->GetOutputPort());
  triangles->PassVertsOff();
  triangles->PassLinesOff();
  triangles->Update();
  vtkPolyData* mesh = triangles->GetOutput();
  if (mesh->GetNumberOfPolys() == 0) return;  // no ground drawn (none enabled)
  Part part;
  part.name = "ground";
  for (vtkIdType i = 0; i < mesh->GetNumberOfPoints(); ++i) Append3(&part.rest, Eigen::Vector3d(mesh->GetPoint(i)));
  auto cell = vtkSmartPointer<vtkIdList>::New();
  vtkCellArray* polys = mesh->GetPolys();
  for (polys->InitTraversal(); polys->GetNextCell(cell);)
    for (vtkIdType i = 0; i < cell->GetNumberOfIds(); ++i) part.triangles.push_back(unsigned(cell->GetId(i)));
  parts_.push_back(std::move(part));
}

// t and R of the frame (Frame, kinematics.h) and γ; a 2D body's R turns about z.
template <int Dim> void GltfRecorder::KeyFfd(Part* part) const {
  const VecQ<double>& q = world_->q(part->body);
  const Frame<Dim, double> frame(q);
  Append3(&part->translation, To3(frame.t));
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  R.topLeftCorner<Dim, Dim>() = frame.R;
  Eigen::Quaterniond r(R);
  r.normalize();
  if (part->rotation.size() >= 4) {  // q and -q are one turn: keep the one nearest the last frame's
    const float* last = &part->rotation[part->rotation.size() - 4];
    if (r.x() * last[0] + r.y() * last[1] + r.z() * last[2] + r.w() * last[3] < 0) r.coeffs() = -r.coeffs();
  }
  for (int i = 0; i < 4; ++i) part->rotation.push_back(float(r.coeffs()[i]));  // x y z w, as glTF
  const double* gamma = q.data() + Group<Dim>::kRigidParams;
  for (size_t d = 0; d < part->targets.size(); ++d) part->weights.push_back(float(gamma[d]));
}

void GltfRecorder::AddFrame() {
  if (!times_.empty() && !(world_->time() > times_.back()))
    throw std::logic_error("GltfRecorder: frame times must increase");
  if (times_.empty()) AddGround();
  times_.push_back(world_->time());
  for (Part& part : parts_) {
    if (part.motion == Part::Motion::kFfd) {
      if (world_->dim(part.body) == 3) KeyFfd<3>(&part);
      else KeyFfd<2>(&part);
    } else if (part.motion == Part::Motion::kLinear) {
      const Eigen::MatrixXd& R = world_->linear_R(part.body);
      for (int i = 0; i < R.rows(); ++i)
        for (int j = 0; j < R.cols(); ++j) part.weights.push_back(float(R(i, j)));
    }
  }
}

void GltfRecorder::AddCameraFrame(const GltfCamera& camera) {
  if (cameras_.size() + 1 != times_.size()) throw std::logic_error("GltfRecorder: one camera per frame, after AddFrame");
  cameras_.push_back(camera);
}

namespace {

// The camera node's rotation: its axes are glTF's (+x right, +y up, looking down −z), so its
// +z is the direction from the focal point to the camera and +y the view-up made orthogonal
// to it (vtkCamera's conventions).
Eigen::Quaterniond CameraRotation(const GltfCamera& c) {
  const Eigen::Vector3d back = (c.position - c.focal_point).normalized();
  const Eigen::Vector3d up = (c.view_up - c.view_up.dot(back) * back).normalized();
  Eigen::Matrix3d axes;
  axes << up.cross(back), up, back;  // columns x, y, z: right-handed (x = y × z)
  return Eigen::Quaterniond(axes).normalized();
}

// The camera node and its keys (AddCameraFrame) into `model`; its properties are the first frame's.
void AddCameraNode(const std::vector<GltfCamera>& cameras, int input, BufferBuilder* buffer, tinygltf::Model* model,
                   tinygltf::Scene* scene, tinygltf::Animation* animation) {
  const GltfCamera& first = cameras.front();
  tinygltf::Camera camera;
  camera.name = "camera";
  double farthest = 0;
  for (const GltfCamera& c : cameras) farthest = std::max(farthest, (c.position - c.focal_point).norm());
  if (first.parallel) {
    camera.type = "orthographic";
    camera.orthographic.ymag = first.parallel_scale;
    camera.orthographic.xmag = first.parallel_scale * first.aspect;
    camera.orthographic.znear = 0.0;
    camera.orthographic.zfar = 2.0 * farthest;  // the focal plane (a 2D world's z = 0) well inside
  } else {
    camera.type = "perspective";
    camera.perspective.yfov = first.view_angle_deg * M_PI / 180.0;
    camera.perspective.aspectRatio = first.aspect;
    camera.perspective.znear = 1e-3 * farthest;
    camera.perspective.zfar = 1e3 * farthest;  // tinygltf writes 0 (invalid) for an infinite one
  }
  model->cameras.push_back(camera);
  tinygltf::Node node;
  node.name = "camera";
  node.camera = int(model->cameras.size()) - 1;
  std::vector<float> translation, rotation;
  for (const GltfCamera& c : cameras) {
    Append3(&translation, c.position);
    Eigen::Quaterniond r = CameraRotation(c);
    if (rotation.size() >= 4) {  // the short way from the last key
      const float* last = &rotation[rotation.size() - 4];
      if (r.x() * last[0] + r.y() * last[1] + r.z() * last[2] + r.w() * last[3] < 0) r.coeffs() = -r.coeffs();
    }
    for (int i = 0; i < 4; ++i) rotation.push_back(float(r.coeffs()[i]));
  }
  node.translation.assign(translation.begin(), translation.begin() + 3);
  node.rotation.assign(rotation.begin(), rotation.begin() + 4);
  model->nodes.push_back(node);
  const int node_index = int(model->nodes.size()) - 1;
  scene->nodes.push_back(node_index);
  for (const auto& [values, type, path] : {std::tuple{&translation, TINYGLTF_TYPE_VEC3, "translation"},
                                           std::tuple{&rotation, TINYGLTF_TYPE_VEC4, "rotation"}}) {
    tinygltf::AnimationSampler sampler;
    sampler.input = input;
    sampler.output = buffer->AddFloats(*values, type == TINYGLTF_TYPE_VEC3 ? 3 : 4, type, false);
    sampler.interpolation = "LINEAR";
    tinygltf::AnimationChannel channel;
    channel.sampler = int(animation->samplers.size());
    channel.target_node = node_index;
    channel.target_path = path;
    animation->samplers.push_back(std::move(sampler));
    animation->channels.push_back(std::move(channel));
  }
}

}  // namespace

std::string GltfRecorder::Bytes() const {
  if (times_.empty()) throw std::logic_error("GltfRecorder: no frame to write");
  tinygltf::Model model;
  model.asset.version = "2.0";
  model.asset.generator = "wobble";
  tinygltf::Material material;  // one light grey, double-sided: outlines and meshes face either way
  material.name = "wobble";
  material.doubleSided = true;
  material.pbrMetallicRoughness.baseColorFactor = {0.8, 0.8, 0.8, 1.0};
  material.pbrMetallicRoughness.metallicFactor = 0.0;
  model.materials.push_back(material);
  BufferBuilder buffer(&model);
  tinygltf::Scene scene;
  tinygltf::Animation animation;
  animation.name = "run";
  const std::vector<float> times(times_.begin(), times_.end());
  const bool has_camera = !cameras_.empty() && cameras_.size() == times_.size();
  const bool moves = has_camera ||
                     std::any_of(parts_.begin(), parts_.end(), [](const Part& p) { return p.motion != Part::Motion::kStatic; });
  const int input = moves ? buffer.AddFloats(times, 1, TINYGLTF_TYPE_SCALAR, true) : -1;

  for (const Part& part : parts_) {
    if (part.triangles.empty() && part.lines.empty()) continue;  // nothing to draw
    tinygltf::Primitive triangles;
    triangles.attributes["POSITION"] = buffer.AddFloats(part.rest, 3, TINYGLTF_TYPE_VEC3, true, true);
    triangles.material = 0;
    tinygltf::Value::Array names;
    for (size_t j = 0; j < part.targets.size(); ++j) {
      triangles.targets.push_back({{"POSITION", buffer.AddFloats(part.targets[j], 3, TINYGLTF_TYPE_VEC3, true, true)}});
      names.emplace_back(part.target_names[j]);
    }
    tinygltf::Primitive lines = triangles;  // the same vertices and targets
    tinygltf::Mesh mesh;
    mesh.name = part.name;
    if (!part.triangles.empty()) {
      triangles.mode = TINYGLTF_MODE_TRIANGLES;
      triangles.indices = buffer.AddIndices(part.triangles);
      mesh.primitives.push_back(std::move(triangles));
    }
    if (!part.lines.empty()) {
      lines.mode = TINYGLTF_MODE_LINE;
      lines.indices = buffer.AddIndices(part.lines);
      mesh.primitives.push_back(std::move(lines));
    }
    if (!names.empty()) {  // Blender and three.js name the shape keys from extras.targetNames
      tinygltf::Value::Object extras;
      extras["targetNames"] = tinygltf::Value(names);
      mesh.extras = tinygltf::Value(extras);
    }
    const int mesh_index = int(model.meshes.size());
    model.meshes.push_back(std::move(mesh));

    tinygltf::Node node;
    node.name = part.name;
    node.mesh = mesh_index;
    if (part.motion == Part::Motion::kFfd) {
      node.translation.assign(part.translation.begin(), part.translation.begin() + 3);
      node.rotation.assign(part.rotation.begin(), part.rotation.begin() + 4);
    }
    node.weights.assign(part.weights.begin(), part.weights.begin() + std::ptrdiff_t(part.targets.size()));
    const int node_index = int(model.nodes.size());
    model.nodes.push_back(std::move(node));
    scene.nodes.push_back(node_index);

    auto animate = [&](const std::vector<float>& values, int components, int type, const char* path) {
      tinygltf::AnimationSampler sampler;
      sampler.input = input;
      sampler.output = buffer.AddFloats(values, components, type, false);
      sampler.interpolation = "LINEAR";
      tinygltf::AnimationChannel channel;
      channel.sampler = int(animation.samplers.size());
      channel.target_node = node_index;
      channel.target_path = path;
      animation.samplers.push_back(std::move(sampler));
      animation.channels.push_back(std::move(channel));
    };
    if (part.motion == Part::Motion::kFfd) {
      animate(part.translation, 3, TINYGLTF_TYPE_VEC3, "translation");
      animate(part.rotation, 4, TINYGLTF_TYPE_VEC4, "rotation");
    }
    // weights: frames × targets scalars (glTF's layout for morph weights); none without targets
    if (part.motion != Part::Motion::kStatic && !part.targets.empty())
      animate(part.weights, 1, TINYGLTF_TYPE_SCALAR, "weights");
  }
  if (has_camera) AddCameraNode(cameras_, input, &buffer, &model, &scene, &animation);
  model.buffers[0].data.resize((model.buffers[0].data.size() + 3) / 4 * 4);  // the BIN chunk's padding
  if (!animation.channels.empty()) model.animations.push_back(std::move(animation));
  model.scenes.push_back(std::move(scene));
  model.defaultScene = 0;

  std::ostringstream stream;
  tinygltf::TinyGLTF writer;
  if (!writer.WriteGltfSceneToStream(&model, stream, false, true))
    throw std::runtime_error("glTF: tinygltf could not serialise the model");
  return stream.str();
}

void GltfRecorder::Write(const std::string& path) const {
  std::string bytes;
  try {
    bytes = Bytes();
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(path + ": " + e.what());
  }
  formats::WriteTextAtomically(path, bytes);  // its errors name the file
}

}  // namespace wobble::pipelines
