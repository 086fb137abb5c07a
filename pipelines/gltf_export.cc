#include "pipelines/gltf_export.h"

#include <tiny_gltf.h>

#include <algorithm>
#include <cstring>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "wobble/dynamics/kinematics.h"
#include "wobble/formats/atomic_file.h"

namespace wobble::pipelines {
namespace {

// Builds the model's one buffer: each Add* appends a float or uint32 array (4-byte aligned, as
// glTF wants for both) as its own bufferView and accessor and returns the accessor's index.
class BufferBuilder {
 public:
  explicit BufferBuilder(tinygltf::Model* model) : model_(model) { model_->buffers.emplace_back(); }

  // `count` elements of `components` floats (type TINYGLTF_TYPE_*); with_bounds: min and max
  // per component, which glTF requires of POSITION (targets too) and animation inputs.
  int AddFloats(const std::vector<float>& values, int components, int type, bool with_bounds) {
    const size_t count = values.size() / size_t(components);
    tinygltf::Accessor a;
    a.bufferView = AddView(values.data(), values.size() * sizeof(float));
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

}  // namespace

GltfRecorder::GltfRecorder(const World* world) : world_(world) {
  for (int b = 0; b < world->num_bodies(); ++b) {
    if (!world->IsFfd(b, 3)) {
      skipped_.push_back(world->body_name(b));
      continue;
    }
    const BodyModelN<3>& model = world->body<3>(b);
    const TriangleMeshN<3>& mesh = model.def().mesh;
    Body body;
    body.index = b;
    body.name = world->body_name(b);
    body.num_modes = model.num_modes();
    body.targets.resize(size_t(body.num_modes));
    // the same b0 and B per vertex that ShapeSource draws the mesh with (world_sources.cc)
    for (int v = 0; v < int(mesh.points.size()); ++v) {
      Append3(&body.rest, model.mesh_rest_local(v));
      const auto B = model.mesh_mode_matrix(v);
      for (int d = 0; d < body.num_modes; ++d) Append3(&body.targets[size_t(d)], B.col(d));
    }
    for (const std::array<int, 3>& t : mesh.triangles)
      for (int i : t) body.triangles.push_back(unsigned(i));
    for (int d = 0; d < body.num_modes; ++d) {
      const std::string& name = model.modes()[size_t(d)].name;
      body.mode_names.push_back(name.empty() ? "mode_" + std::to_string(d + 1) : name);
    }
    bodies_.push_back(std::move(body));
  }
}

void GltfRecorder::AddFrame() {
  if (!times_.empty() && !(world_->time() > times_.back()))
    throw std::logic_error("GltfRecorder: frame times must increase");
  times_.push_back(world_->time());
  for (Body& body : bodies_) {
    const VecQ<double>& q = world_->q(body.index);
    Append3(&body.translation, q.head<3>());
    // R of the state, as Frame (kinematics.h) makes it: the quaternion of q (Group<3>)
    Eigen::Quaterniond r = Group<3>::OrientationOf(q).normalized();
    if (body.rotation.size() >= 4) {  // q and -q are one turn: keep the one nearest the last frame's
      const float* last = &body.rotation[body.rotation.size() - 4];
      if (r.x() * last[0] + r.y() * last[1] + r.z() * last[2] + r.w() * last[3] < 0) r.coeffs() = -r.coeffs();
    }
    for (int i = 0; i < 4; ++i) body.rotation.push_back(float(r.coeffs()[i]));  // x y z w, as glTF
    const double* gamma = q.data() + Group<3>::kRigidParams;
    for (int d = 0; d < body.num_modes; ++d) body.weights.push_back(float(gamma[d]));
  }
}

std::string GltfRecorder::Bytes() const {
  if (times_.empty()) throw std::logic_error("GltfRecorder: no frame to write");
  tinygltf::Model model;
  model.asset.version = "2.0";
  model.asset.generator = "wobble";
  BufferBuilder buffer(&model);
  tinygltf::Scene scene;
  tinygltf::Animation animation;
  animation.name = "run";
  const std::vector<float> times(times_.begin(), times_.end());
  const int input = bodies_.empty() ? -1 : buffer.AddFloats(times, 1, TINYGLTF_TYPE_SCALAR, true);

  for (const Body& body : bodies_) {
    tinygltf::Primitive primitive;
    primitive.mode = TINYGLTF_MODE_TRIANGLES;
    primitive.attributes["POSITION"] = buffer.AddFloats(body.rest, 3, TINYGLTF_TYPE_VEC3, true);
    primitive.indices = buffer.AddIndices(body.triangles);
    tinygltf::Value::Array names;
    for (int d = 0; d < body.num_modes; ++d) {
      primitive.targets.push_back({{"POSITION", buffer.AddFloats(body.targets[size_t(d)], 3, TINYGLTF_TYPE_VEC3, true)}});
      names.emplace_back(body.mode_names[size_t(d)]);
    }
    tinygltf::Mesh mesh;
    mesh.name = body.name;
    mesh.primitives.push_back(std::move(primitive));
    mesh.weights.assign(size_t(body.num_modes), 0.0);
    if (body.num_modes > 0) {  // Blender and three.js name the shape keys from extras.targetNames
      tinygltf::Value::Object extras;
      extras["targetNames"] = tinygltf::Value(names);
      mesh.extras = tinygltf::Value(extras);
    }
    const int mesh_index = int(model.meshes.size());
    model.meshes.push_back(std::move(mesh));

    tinygltf::Node node;
    node.name = body.name;
    node.mesh = mesh_index;
    node.translation.assign(body.translation.begin(), body.translation.begin() + 3);
    node.rotation.assign(body.rotation.begin(), body.rotation.begin() + 4);
    node.weights.assign(body.weights.begin(), body.weights.begin() + body.num_modes);
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
    animate(body.translation, 3, TINYGLTF_TYPE_VEC3, "translation");
    animate(body.rotation, 4, TINYGLTF_TYPE_VEC4, "rotation");
    // weights: frames × modes scalars (glTF's layout for morph weights); a body without modes has none
    if (body.num_modes > 0) animate(body.weights, 1, TINYGLTF_TYPE_SCALAR, "weights");
  }
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
