// The ground as terrain (issue 19): `terrain` sets the profile, `terrain_face` a segment's own
// penalty parameters (the names `set` gives the ground's: grconst, grdam, frconst, frsin);
// `heightfield` the 3D objects' ground, `heightfield_region` its cells' own parameters.
#include "wobble/formats/heightfield_file.h"
#include "wobble/script/internal/interpreter_internal.h"

namespace wobble::script {

using namespace script_detail;

namespace {

Ground& TheGround(State& s) { return s.scene.options().params.ground; }

// Terrain::Make's refusals are this line's bad input.
std::shared_ptr<const Terrain> MakeTerrain(std::vector<Eigen::Vector2d> vertices, std::vector<SurfaceOverrides> faces,
                                           const Context& ctx) {
  try {
    return Terrain::Make(std::move(vertices), std::move(faces));
  } catch (const InputError& e) {
    ctx.Fail(e.what());
  }
}

}  // namespace

void TerrainCommand(State& s, const Words& w, const Context& ctx) {
  if (w.size() == 2 && w[1] == "off") {
    TheGround(s).terrain = nullptr;
    return;
  }
  if (w.size() < 5 || w.size() % 2 == 0) ctx.Fail("expected 'terrain X1 Y1 X2 Y2 ...' (pairs, at least two) or 'terrain off'");
  std::vector<Eigen::Vector2d> vertices;
  for (size_t i = 1; i + 1 < w.size(); i += 2) {
    const std::string n = std::to_string((i + 1) / 2);
    vertices.emplace_back(Number(w[i], "X" + n, ctx), Number(w[i + 1], "Y" + n, ctx));
  }
  TheGround(s).terrain = MakeTerrain(std::move(vertices), {}, ctx);
}

void TerrainFaceCommand(State& s, const Words& w, const Context& ctx) {
  if (w.size() < 4 || w.size() % 2 != 0) ctx.Fail("expected '" + ctx.usage + "'");
  const std::shared_ptr<const Terrain>& terrain = TheGround(s).terrain;
  if (!terrain) ctx.Fail("no terrain yet: 'terrain X1 Y1 X2 Y2 ...' first");
  const int segments = int(terrain->vertices().size()) - 1;
  const double index = Number(w[1], "SEGMENT", ctx);
  if (!(index >= 1 && index <= segments && index == std::floor(index)))
    ctx.Fail("expected a segment from 1 to " + std::to_string(segments) + ", got " + w[1]);
  std::vector<SurfaceOverrides> faces = terrain->segments();
  faces.resize(size_t(segments));
  SurfaceOverrides& face = faces[size_t(index) - 1];
  for (size_t i = 2; i + 1 < w.size(); i += 2)
    if (!face.Set(w[i], NonNegative(w[i + 1], w[i], ctx)))
      ctx.Fail("expected grconst, grdam, frconst or frsin, got '" + w[i] + "'" + DidYouMean(w[i], SurfaceOverrides::Names()));
  TheGround(s).terrain = MakeTerrain(terrain->vertices(), std::move(faces), ctx);
}

void HeightfieldCommand(State& s, const Words& w, const Context& ctx) {
  if (w.size() != 2) ctx.Fail("expected 'heightfield FILE' or 'heightfield off'");
  TheGround(s).heightfield = w[1] == "off" ? nullptr : formats::ReadHeightfieldFile(Resolve(w[1], ctx.dir));
}

void HeightfieldRegionCommand(State& s, const Words& w, const Context& ctx) {
  if (w.size() < 7 || w.size() % 2 == 0) ctx.Fail("expected '" + ctx.usage + "'");
  const std::shared_ptr<const Heightfield>& field = TheGround(s).heightfield;
  if (!field) ctx.Fail("no heightfield yet: 'heightfield FILE' first");
  const Eigen::Vector2d lo(Number(w[1], "X0", ctx), Number(w[2], "Z0", ctx));
  const Eigen::Vector2d hi(Number(w[3], "X1", ctx), Number(w[4], "Z1", ctx));
  SurfaceOverrides constants;
  for (size_t i = 5; i + 1 < w.size(); i += 2)
    if (!constants.Set(w[i], NonNegative(w[i + 1], w[i], ctx)))
      ctx.Fail("expected grconst, grdam, frconst or frsin, got '" + w[i] + "'" + DidYouMean(w[i], SurfaceOverrides::Names()));
  try {
    TheGround(s).heightfield = field->WithRegion(lo, hi, constants);
  } catch (const InputError& e) {
    ctx.Fail(e.what());
  }
}

}  // namespace wobble::script
