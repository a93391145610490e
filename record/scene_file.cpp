#include "record/scene_file.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <set>
#include <sstream>

#include "base/check.h"
#include "base/file.h"
#include "base/format.h"
#include "base/parse.h"
#include "base/toml_read.h"
#include "record/vec3.h"

namespace raycell {
namespace {

constexpr double kPi = 3.14159265358979323846;

// ---------------------------------------------------------------------------------------------
// Numbers and colours in --material and --light text.

double ParseNumber(const std::string& text, const std::string& what) {
  std::size_t used = 0;
  double v = 0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size() || !std::isfinite(v)) {
    throw InputError(what + ": '" + text + "' is not a finite number");
  }
  return v;
}

Vec3d ParseTriple(const std::string& text, const std::string& what) {
  const auto parts = Split(text, ',');
  if (parts.size() != 3) throw InputError(what + ": expected X,Y,Z, got '" + text + "'");
  return {ParseNumber(parts[0], what), ParseNumber(parts[1], what), ParseNumber(parts[2], what)};
}

Rgb ToRgb(const std::vector<double>& v, const std::string& what) {
  if (v.size() == 1) return {v[0], v[0], v[0]};  // one number means grey
  if (v.size() != 3) throw InputError(what + ": expected one number or R,G,B");
  return {v[0], v[1], v[2]};
}

double One(const std::vector<double>& v, const std::string& what) {
  if (v.size() != 1) throw InputError(what + ": expected one number");
  return v[0];
}

void RequireNonNegative(const Rgb& c, const std::string& what) {
  if (c.r < 0 || c.g < 0 || c.b < 0) throw InputError(what + ": must not be negative");
}

void RequireAtMost(const Rgb& c, double limit, const std::string& what, const char* why) {
  if (c.r > limit || c.g > limit || c.b > limit) {
    std::ostringstream s;
    s << what << ": must be at most " << limit << " (" << why << ")";
    throw InputError(s.str());
  }
}

// Light colours are bounded so that radiance fits a float in the single-precision marcher
// (it never exceeds the sum of the lights: surface colours and albedos are at most 1).
constexpr double kMaxLight = 1e30;

double Fraction(const std::vector<double>& v, const std::string& what) {
  const double f = One(v, what);
  if (!(f >= 0 && f <= 1)) throw InputError(what + ": must be in [0, 1], got " + FormatReal(f));
  return f;
}

}  // namespace

std::vector<double> ParseMaterialValues(const std::string& text, const std::string& what) {
  if (text.find(',') == std::string::npos) return {ParseNumber(text, what)};
  const Vec3d v = ParseTriple(text, what);
  return {v.x, v.y, v.z};
}

void SetFogKey(FogMaterial& m, const std::string& key, const std::vector<double>& values,
               const std::string& what) {
  for (double v : values) {
    if (!std::isfinite(v)) throw InputError(what + ": must be finite");
  }
  if (key == "absorb") {
    m.absorption = ToRgb(values, what);
    RequireNonNegative(m.absorption, what);
  } else if (key == "scatter") {
    m.scattering = ToRgb(values, what);
    RequireNonNegative(m.scattering, what);
  } else if (key == "gain") {
    m.shadow_gain = One(values, what);
    if (m.shadow_gain < 0) throw InputError(what + ": must not be negative");
  } else {
    throw InputError(what + ": unknown fog material key (known: absorb, scatter, gain)");
  }
}

void SetSurfaceKey(SurfaceMaterial& m, const std::string& key, const std::vector<double>& values,
                   const std::string& what) {
  for (double v : values) {
    if (!std::isfinite(v)) throw InputError(what + ": must be finite");
  }
  if (key == "color") {
    m.color = ToRgb(values, what);
    RequireNonNegative(m.color, what);
    RequireAtMost(m.color, 1.0, what, "a surface reflects at most the light it gets");
  } else if (key == "reflect") {
    m.reflectivity = Fraction(values, what);
  } else if (key == "transparency") {
    m.transparency = Fraction(values, what);
  } else if (key == "ior") {
    m.ior = One(values, what);
    if (!(m.ior >= 1.0 && m.ior <= 10.0)) throw InputError(what + ": must be in [1, 10]");
  } else {
    throw InputError(what +
                     ": unknown surface material key (known: color, reflect, transparency, ior)");
  }
}

void CheckSurfaceMaterial(const SurfaceMaterial& m, const std::string& what) {
  if (m.reflectivity + m.transparency > 1.0) {
    throw InputError(what + ": reflect + transparency must not exceed 1");
  }
}

void ValidateLight(const Light& l, const std::string& what) {
  if (!IsFinite(l.v)) throw InputError(what + ": position or direction must be finite");
  if (!(std::isfinite(l.color.r) && std::isfinite(l.color.g) && std::isfinite(l.color.b))) {
    throw InputError(what + ": colour must be finite");
  }
  RequireNonNegative(l.color, what);
  RequireAtMost(l.color, kMaxLight, what, "radiance must fit a float");
  if (l.type == Light::Type::kDirectional && !(Length(l.v) > 0)) {
    throw InputError(what + ": direction must not be zero");
  }
}

Light ParseLight(const std::string& text) {
  const auto f = Split(text, ':');
  const std::string what = "--light '" + text + "'";
  if (f.size() < 2 || f.size() > 3 || (f[0] != "dir" && f[0] != "point")) {
    throw InputError(what + ": expected dir:X,Y,Z[:R,G,B] or point:X,Y,Z[:R,G,B]");
  }
  Light l;
  l.type = f[0] == "dir" ? Light::Type::kDirectional : Light::Type::kPoint;
  l.v = ParseTriple(f[1], what);
  if (f.size() == 3) l.color = ToRgb(ParseMaterialValues(f[2], what), what);
  ValidateLight(l, what);
  return l;
}

bool IsSequencePattern(const std::string& source) { return source.find('%') != std::string::npos; }

std::string FrameFile(const std::string& source, int frame) {
  if (!IsSequencePattern(source)) return source;
  char buf[4096];
  const int n = std::snprintf(buf, sizeof buf, source.c_str(), frame);
  if (n < 0 || n >= int(sizeof buf)) throw InputError("--scene '" + source + "': bad pattern");
  return buf;
}

namespace {

// ---------------------------------------------------------------------------------------------
// Reading TOML: every key read is marked; a key nothing read is an error naming its line.

class Table {
 public:
  // `label` prefixes keys in messages: "grid 'cloud' " or "camera.".
  Table(const toml::table& t, std::string label, const std::string& file)
      : t_(t), label_(std::move(label)), file_(file) {}

  const toml::node* Get(const char* key) {
    used_.insert(key);
    return t_.get(key);
  }
  int line() const { return int(t_.source().begin.line); }
  std::string What(const toml::node& n, const std::string& key) const {
    return TomlWhere(file_, n.source()) + ": " + label_ + key;
  }
  [[noreturn]] void Fail(const toml::node& n, const std::string& key,
                         const std::string& message) const {
    throw InputError(What(n, key) + ": " + message);
  }
  [[noreturn]] void TypeError(const toml::node& n, const std::string& key,
                              const char* expected) const {
    Fail(n, key, std::string("expected ") + expected + ", got " + TomlTypeName(n));
  }

  double Number(const toml::node& n, const std::string& key) const {
    double v = 0;
    if (n.is_integer()) {
      v = double(n.as_integer()->get());
    } else if (n.is_floating_point()) {
      v = n.as_floating_point()->get();
    } else {
      TypeError(n, key, "a number");
    }
    if (!std::isfinite(v)) Fail(n, key, "must be a finite number, got " + FormatReal(v));
    return v;
  }
  // The key's number if present (else `def`), in [lo, hi] (open ends when `open`).
  double Real(const char* key, double def, double lo, double hi, bool open_lo = false) {
    const toml::node* n = Get(key);
    if (n == nullptr) return def;
    const double v = Number(*n, key);
    if (v < lo || v > hi || (open_lo && v == lo)) {
      Fail(*n, key,
           "must be in " + std::string(open_lo ? "(" : "[") + FormatReal(lo) + ", " +
               FormatReal(hi) + "], got " + FormatReal(v));
    }
    return v;
  }
  std::int64_t Int(const char* key, std::int64_t def, std::int64_t lo, std::int64_t hi) {
    const toml::node* n = Get(key);
    if (n == nullptr) return def;
    if (!n->is_integer()) TypeError(*n, key, "an integer");
    const std::int64_t v = n->as_integer()->get();
    if (v < lo || v > hi) {
      Fail(*n, key,
           "must be in " + std::to_string(lo) + ".." + std::to_string(hi) + ", got " +
               std::to_string(v));
    }
    return v;
  }
  std::vector<double> Values(const toml::node& n, const std::string& key) const {
    if (const toml::array* a = n.as_array()) {
      std::vector<double> out;
      for (const toml::node& e : *a) out.push_back(Number(e, key));
      if (out.size() != 3) Fail(n, key, "expected 3 numbers, got " + std::to_string(out.size()));
      return out;
    }
    return {Number(n, key)};
  }
  Vec3d Vec(const toml::node& n, const std::string& key) const {
    if (!n.is_array()) TypeError(n, key, "an array of 3 numbers [x, y, z]");
    const auto v = Values(n, key);
    return {v[0], v[1], v[2]};
  }
  // A vector key, |components| at most kMaxCoordinate.
  Vec3d VecKey(const char* key, Vec3d def) {
    const toml::node* n = Get(key);
    if (n == nullptr) return def;
    const Vec3d v = Vec(*n, key);
    CheckCoordinate(*n, key, v);
    return v;
  }
  Rgb Color(const char* key, Rgb def, double max) {
    const toml::node* n = Get(key);
    if (n == nullptr) return def;
    const Rgb c = ToRgb(Values(*n, key), What(*n, key));
    if (c.r < 0 || c.g < 0 || c.b < 0 || c.r > max || c.g > max || c.b > max) {
      Fail(*n, key, "each component must be in [0, " + FormatReal(max) + "]");
    }
    return c;
  }
  std::string String(const char* key, const std::string& def) {
    const toml::node* n = Get(key);
    if (n == nullptr) return def;
    if (!n->is_string()) TypeError(*n, key, "a string");
    return n->as_string()->get();
  }
  const toml::table* SubTable(const char* key) {
    const toml::node* n = Get(key);
    if (n == nullptr) return nullptr;
    if (!n->is_table()) TypeError(*n, key, "a table");
    return n->as_table();
  }
  // An array of tables ([[key]]), or nothing.
  std::vector<const toml::table*> Tables(const char* key) {
    std::vector<const toml::table*> out;
    const toml::node* n = Get(key);
    if (n == nullptr) return out;
    const toml::array* a = n->as_array();
    if (a == nullptr) Fail(*n, key, "expected an array of tables ([[" + std::string(key) + "]])");
    for (const toml::node& e : *a) {
      if (!e.is_table()) TypeError(e, key, "a table");
      out.push_back(e.as_table());
    }
    return out;
  }
  void CheckCoordinate(const toml::node& n, const std::string& key, Vec3d v) const {
    for (double c : {v.x, v.y, v.z}) {
      if (std::fabs(c) > kMaxCoordinate) {
        Fail(n, key, "each coordinate must be within +-" + FormatReal(kMaxCoordinate));
      }
    }
  }
  void ReportUnused() const {
    const toml::key* first = FirstUnusedKey(t_, used_);
    if (first == nullptr) return;
    const std::string valid = JoinKeys(used_);
    std::string in(Trim(label_));
    if (!in.empty() && in.back() == '.') in.pop_back();
    throw InputError(TomlWhere(file_, first->source()) + ": unknown key '" +
                     std::string(first->str()) + "'" + (in.empty() ? "" : " in " + in) +
                     " (valid keys here: " + valid + ")");
  }
  const std::string& file() const { return file_; }
  const std::string& label() const { return label_; }

  static constexpr double kMaxCoordinate = 1e6;

 private:
  const toml::table& t_;
  std::string label_;
  const std::string& file_;
  std::set<std::string> used_;
};

const std::vector<std::string>& PlatonicTypes() {
  static const std::vector<std::string> types = {"tetrahedron", "cube", "octahedron",
                                                 "dodecahedron", "icosahedron"};
  return types;
}

bool IsPlatonic(const std::string& type) {
  const auto& p = PlatonicTypes();
  return std::find(p.begin(), p.end(), type) != p.end();
}

const char* OpName(ShapeDesc::Op op) {
  switch (op) {
    case ShapeDesc::Op::kUnion:
      return "union";
    case ShapeDesc::Op::kDifference:
      return "difference";
    default:
      return "intersection";
  }
}

ShapeDesc ReadShape(const toml::table& t, const std::string& grid, std::size_t index,
                    const std::string& file) {
  Table s(t, "grid '" + grid + "' shape " + std::to_string(index + 1) + " ", file);
  ShapeDesc shape;
  shape.line = s.line();
  const toml::node* type = s.Get("type");
  if (type == nullptr) {
    throw InputError(TomlWhere(file, t.source()) + ": " + s.label() +
                     "missing required key 'type' (sphere, box, " + Join(PlatonicTypes(), ", ") +
                     ")");
  }
  shape.type = s.String("type", "");
  const std::string op = s.String("op", "union");
  if (op == "union") {
    shape.op = ShapeDesc::Op::kUnion;
  } else if (op == "difference") {
    shape.op = ShapeDesc::Op::kDifference;
  } else if (op == "intersection") {
    shape.op = ShapeDesc::Op::kIntersection;
  } else {
    s.Fail(*s.Get("op"), "op", "expected union, difference or intersection, got '" + op + "'");
  }
  if (shape.type == "sphere") {
    shape.center = s.VecKey("center", shape.center);
    shape.radius = s.Real("radius", shape.radius, 0, Table::kMaxCoordinate, true);
  } else if (IsPlatonic(shape.type)) {
    shape.center = s.VecKey("center", shape.center);
    shape.scale = s.Real("scale", shape.scale, 0, Table::kMaxCoordinate, true);
  } else if (shape.type == "box") {
    shape.min = s.VecKey("min", shape.min);
    shape.max = s.VecKey("max", shape.max);
    if (!(shape.min.x < shape.max.x && shape.min.y < shape.max.y && shape.min.z < shape.max.z)) {
      const toml::node* mx = s.Get("max");
      s.Fail(mx ? *mx : *type, "max", "must exceed min on every axis");
    }
  } else {
    s.Fail(*type, "type",
           "unknown shape '" + shape.type + "' (known: sphere, box, " +
               Join(PlatonicTypes(), ", ") + ")");
  }
  s.ReportUnused();
  return shape;
}

void ReadMaterial(const toml::table& t, GridDesc& g, const std::string& file) {
  Table m(t, "grid '" + g.name + "' material.", file);
  const std::vector<const char*> keys =
      g.fog ? std::vector<const char*>{"absorb", "scatter", "gain"}
            : std::vector<const char*>{"color", "reflect", "transparency", "ior"};
  for (const char* key : keys) {
    const toml::node* n = m.Get(key);
    if (n == nullptr) continue;
    const std::vector<double> v = m.Values(*n, key);
    g.fog ? SetFogKey(g.fog_material, key, v, m.What(*n, key))
          : SetSurfaceKey(g.surface_material, key, v, m.What(*n, key));
  }
  try {
    m.ReportUnused();
  } catch (const InputError& e) {
    throw InputError(std::string(e.what()) + (g.fog ? "; a fog's material keys are absorb, "
                                                      "scatter, gain"
                                                    : "; a surface's material keys are color, "
                                                      "reflect, transparency, ior"));
  }
  if (!g.fog) CheckSurfaceMaterial(g.surface_material, TomlWhere(file, t.source()) + ": " + g.name);
}

void ReadNoise(const toml::table& t, GridDesc& g, const std::string& file) {
  Table n(t, "grid '" + g.name + "' noise.", file);
  NoiseDesc& d = g.noise;
  d.on = true;
  d.seed = std::uint64_t(n.Int("seed", 0, 0, std::numeric_limits<std::int64_t>::max()));
  const toml::node* period = n.Get("period");
  d.period = int(n.Int("period", d.period, 1, 256));
  if ((d.period & (d.period - 1)) != 0) {
    n.Fail(*period, "period", "must be a power of two (1, 2, 4, ..., 256)");
  }
  const toml::node* octaves = n.Get("octaves");
  d.octaves = int(n.Int("octaves", d.octaves, 1, 8));
  if ((d.period >> (d.octaves - 1)) < 1) {
    n.Fail(*octaves, "octaves",
           "each octave halves the period: at most log2(period) + 1 = " +
               std::to_string(int(std::log2(d.period)) + 1) + " here");
  }
  d.amount = n.Real("amount", d.amount, 0, 1);
  d.threshold = n.Real("threshold", d.threshold, 0, 1);
  n.ReportUnused();
}

void ReadAnimate(const toml::table& t, GridDesc& g, const std::string& file) {
  Table a(t, "grid '" + g.name + "' animate.", file);
  g.animate.translate = a.VecKey("translate", g.animate.translate);
  g.animate.rotate = a.Real("rotate", 0, -360, 360);
  const toml::node* grow = a.Get("grow");
  g.animate.grow = a.Real("grow", 0, -Table::kMaxCoordinate, Table::kMaxCoordinate);
  if (grow != nullptr && g.from_file()) {
    a.Fail(*grow, "grow", "a grid read from a file has no shapes to grow");
  }
  a.ReportUnused();
}

GridDesc ReadGrid(const toml::table& t, std::size_t index, const std::string& file,
                  const std::string& dir) {
  GridDesc g;
  g.line = int(t.source().begin.line);
  Table pre(t, "", file);
  const toml::node* name = pre.Get("name");
  if (name == nullptr) {
    throw InputError(TomlWhere(file, t.source()) + ": grid " + std::to_string(index + 1) +
                     ": missing required key 'name'");
  }
  g.name = pre.String("name", "");
  if (g.name.empty() || g.name.find(':') != std::string::npos) {
    pre.Fail(*name, "name", "must be non-empty without ':' (--material GRID:key=value names it)");
  }
  Table s(t, "grid '" + g.name + "' ", file);
  s.Get("name");
  const std::string role = s.String("role", "");
  if (!role.empty() && role != "fog" && role != "surface") {
    s.Fail(*s.Get("role"), "role", "expected fog or surface, got '" + role + "'");
  }
  g.fog = role == "fog";
  const toml::node* file_node = s.Get("file");
  const std::string file_text = s.String("file", "");
  const std::vector<const toml::table*> shapes = s.Tables("shape");
  if (file_node != nullptr) {
    if (file_text.empty()) s.Fail(*file_node, "file", "must not be empty");
    if (!shapes.empty()) s.Fail(*file_node, "file", "give a file or shapes, not both");
    if (role.empty()) {
      s.Fail(*file_node, "role",
             "a grid read from a file needs role = \"fog\" or \"surface\" (a level set given "
             "role = \"fog\" becomes fog)");
    }
    namespace fs = std::filesystem;
    const fs::path p(file_text);
    g.file = (p.is_absolute() ? p : fs::absolute(fs::path(dir) / p)).lexically_normal().string();
    g.vdb_grid = s.String("grid", "");
  } else {
    if (shapes.empty()) {
      throw InputError(TomlWhere(file, t.source()) + ": grid '" + g.name +
                       "': give file = \"PATH.vdb\" or at least one [[grid.shape]]");
    }
    for (std::size_t i = 0; i < shapes.size(); ++i) {
      g.shapes.push_back(ReadShape(*shapes[i], g.name, i, file));
    }
  }
  const toml::node* voxel = s.Get("voxel");
  const toml::node* band = s.Get("band");
  if (g.from_file() && (voxel || band)) {
    s.Fail(voxel ? *voxel : *band, voxel ? "voxel" : "band",
           "a grid read from a file has its own voxels and band");
  }
  g.voxel = s.Real("voxel", g.voxel, 0, 1e3, true);
  g.band = s.Real("band", g.band, 1, 64);
  const toml::node* ramp = s.Get("ramp");
  g.ramp = s.Real("ramp", 0, 0, Table::kMaxCoordinate);
  if (ramp != nullptr && !g.fog) s.Fail(*ramp, "ramp", "only a fog has a density ramp");
  g.scale = s.Real("scale", 1, 0, 1e6, true);
  g.translate = s.VecKey("translate", g.translate);
  if (const toml::table* r = s.SubTable("rotate")) {
    Table rt(*r, "grid '" + g.name + "' rotate.", file);
    g.axis = rt.VecKey("axis", g.axis);
    g.degrees = rt.Real("degrees", 0, -360, 360);
    const toml::node* axis = rt.Get("axis");
    if (!(Length(g.axis) > 0)) rt.Fail(axis ? *axis : *r, "axis", "must not be zero");
    rt.ReportUnused();
  }
  if (const toml::table* n = s.SubTable("noise")) {
    if (!g.fog) s.Fail(*s.Get("noise"), "noise", "noise modulates a fog's density: role = \"fog\"");
    ReadNoise(*n, g, file);
  }
  if (const toml::table* a = s.SubTable("animate")) ReadAnimate(*a, g, file);
  if (const toml::table* m = s.SubTable("material")) ReadMaterial(*m, g, file);
  s.ReportUnused();
  return g;
}

Light ReadLight(const toml::table& t, std::size_t index, const std::string& file) {
  Table s(t, "light " + std::to_string(index + 1) + " ", file);
  Light l;
  const std::string type = s.String("type", "dir");
  if (type != "dir" && type != "point") {
    s.Fail(*s.Get("type"), "type", "expected dir or point, got '" + type + "'");
  }
  l.type = type == "dir" ? Light::Type::kDirectional : Light::Type::kPoint;
  const char* vkey = type == "dir" ? "direction" : "position";
  const toml::node* v = s.Get(vkey);
  if (v == nullptr) {
    throw InputError(TomlWhere(file, t.source()) + ": light " + std::to_string(index + 1) +
                     ": missing required key '" + vkey + "'");
  }
  l.v = s.VecKey(vkey, l.v);
  l.color = s.Color("color", l.color, kMaxLight);
  ValidateLight(l, TomlWhere(file, t.source()) + ": light " + std::to_string(index + 1));
  s.ReportUnused();
  return l;
}

void ReadCamera(const toml::table& t, SceneDescription& d, const std::string& file) {
  Table s(t, "camera.", file);
  CameraPathSpec& c = d.camera;
  c.eye = s.VecKey("eye", c.eye);
  c.target = s.VecKey("target", c.target);
  const toml::node* up = s.Get("up");
  c.up = s.VecKey("up", c.up);
  if (!(Length(c.up) > 0)) s.Fail(*up, "up", "must not be zero");
  c.fov_deg = s.Real("fov", c.fov_deg, 0, 180, true);
  if (c.fov_deg == 180) s.Fail(*s.Get("fov"), "fov", "must be below 180 degrees");
  if (const toml::table* o = s.SubTable("orbit")) {
    Table ot(*o, "camera.orbit.", file);
    c.orbit_degrees = ot.Real("degrees", 0, -1e6, 1e6);
    c.orbit_frames = int(ot.Int("frames", 0, 0, 1000000));
    if (ot.Get("degrees") == nullptr) {
      throw InputError(TomlWhere(file, o->source()) +
                       ": camera.orbit: missing required key "
                       "'degrees'");
    }
    ot.ReportUnused();
  }
  const auto keys = s.Tables("key");
  if (!keys.empty() && s.Get("orbit") != nullptr) {
    s.Fail(*s.Get("key"), "key", "give an orbit or key frames, not both");
  }
  for (std::size_t i = 0; i < keys.size(); ++i) {
    Table k(*keys[i], "camera key " + std::to_string(i + 1) + " ", file);
    CameraKey key;
    const toml::node* frame = k.Get("frame");
    if (frame == nullptr || !k.Get("eye") || !k.Get("target")) {
      throw InputError(TomlWhere(file, keys[i]->source()) + ": camera key " +
                       std::to_string(i + 1) + ": needs frame, eye and target");
    }
    key.frame = int(k.Int("frame", 0, -1000000000, 1000000000));
    key.eye = k.VecKey("eye", key.eye);
    key.target = k.VecKey("target", key.target);
    key.fov_deg = k.Real("fov", c.fov_deg, 0, 180, true);
    if (key.fov_deg == 180) k.Fail(*k.Get("fov"), "fov", "must be below 180 degrees");
    key.up = c.up;
    if (!c.keys.empty() && key.frame <= c.keys.back().frame) {
      k.Fail(*frame, "frame", "key frames must increase");
    }
    if (key.eye == key.target) k.Fail(*k.Get("eye"), "eye", "must differ from target");
    k.ReportUnused();
    c.keys.push_back(key);
  }
  if (IsFinite(c.eye) && IsFinite(c.target) && c.eye == c.target) {
    s.Fail(*s.Get("eye"), "eye", "must differ from target");
  }
  s.ReportUnused();
}

// The voxels a grid of these shapes may allocate: its narrow band (each shape's area times
// the band's width), and with noise its whole inside (noise voxelizes the fog's tiles).
double EstimateVoxels(const GridDesc& g, const std::vector<ShapeDesc>& shapes) {
  double area = 0, volume = 0;
  for (const ShapeDesc& s : shapes) {
    if (s.type == "box") {
      const Vec3d e = s.max - s.min;
      area += 2 * (e.x * e.y + e.y * e.z + e.z * e.x);
      volume += e.x * e.y * e.z;
    } else {
      // OpenVDB's platonic solids have their vertices at distance `scale` from the centre:
      // their circumscribed sphere bounds them.
      const double r = s.type == "sphere" ? s.radius : s.scale;
      area += 4 * kPi * r * r;
      volume += 4.0 / 3.0 * kPi * r * r * r;
    }
  }
  const double v = g.voxel;
  return area / (v * v) * (2 * g.band + 2) + (g.noise.on ? volume / (v * v * v) : 0);
}

void CheckShapes(const GridDesc& g, const std::vector<ShapeDesc>& shapes, const std::string& what) {
  for (const ShapeDesc& s : shapes) {
    const std::string where =
        what + " shape " + s.type + (s.line ? " (line " + std::to_string(s.line) + ")" : "");
    if (s.type == "sphere" && !(s.radius > 0)) {
      throw InputError(where + ": radius " + FormatReal(s.radius) + " must be positive");
    }
    if (IsPlatonic(s.type) && !(s.scale > 0)) {
      throw InputError(where + ": scale " + FormatReal(s.scale) + " must be positive");
    }
    if (s.type == "box" && !(s.min.x < s.max.x && s.min.y < s.max.y && s.min.z < s.max.z)) {
      throw InputError(where + ": max must exceed min on every axis");
    }
    // Index coordinates must fit OpenVDB's 32-bit Coord with room for the band.
    const double reach =
        std::max({std::fabs(s.center.x), std::fabs(s.center.y), std::fabs(s.center.z),
                  std::fabs(s.min.x), std::fabs(s.min.y), std::fabs(s.min.z), std::fabs(s.max.x),
                  std::fabs(s.max.y), std::fabs(s.max.z)}) +
        std::max(s.radius, s.scale);
    if (reach / g.voxel > double(1 << 28)) {
      throw InputError(where + ": " + FormatReal(reach / g.voxel) +
                       " voxels from the origin; at most 2^28 (OpenVDB's coordinates)");
    }
  }
  const double voxels = EstimateVoxels(g, shapes);
  if (voxels > kMaxGridVoxels) {
    std::ostringstream s;
    s << what << ": about " << voxels << " voxels at voxel size " << FormatReal(g.voxel)
      << " exceeds the limit of " << kMaxGridVoxels
      << " (2^27, half a GiB of floats); give a larger voxel or smaller shapes";
    throw InputError(s.str());
  }
}

// TOML text for a string (a basic string with escapes).
std::string Quote(const std::string& s) {
  std::string out = "\"";
  for (unsigned char ch : s) {
    if (ch == '"' || ch == '\\') {
      out += '\\';
      out += char(ch);
    } else if (ch < 0x20 || ch == 0x7f) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", ch);
      out += buf;
    } else {
      out += char(ch);
    }
  }
  return out + "\"";
}

// A number as TOML reads it back to the same double ("-0" would be the integer 0).
std::string Num(double v) { return v == 0 && std::signbit(v) ? "-0.0" : FormatReal(v); }
std::string Vec(Vec3d v) { return "[" + Num(v.x) + ", " + Num(v.y) + ", " + Num(v.z) + "]"; }
std::string Col(Rgb c) { return "[" + Num(c.r) + ", " + Num(c.g) + ", " + Num(c.b) + "]"; }

}  // namespace

bool SceneDescription::animated() const {
  return std::any_of(grids.begin(), grids.end(), [](const GridDesc& g) { return g.animated(); });
}

bool VolumeChanges(const SceneSpec& spec) {
  if (spec.description) return spec.description->animated();
  if (IsSceneFile(spec.source)) return LoadSceneDescription(spec.source).animated();
  return IsSequencePattern(spec.source);
}

std::string SceneLabel(const SceneSpec& spec) {
  if (!spec.description && !IsSceneFile(spec.source)) return spec.source;
  const SceneDescription d =
      spec.description ? *spec.description : LoadSceneDescription(spec.source);
  return d.animated() ? d.name + "@%d" : d.name;
}

bool IsSceneFile(const std::string& source) {
  return source == "builtin" ||
         (source.size() > 5 && source.compare(source.size() - 5, 5, ".toml") == 0);
}

std::vector<ShapeDesc> ShapesAtFrame(const GridDesc& g, int frame) {
  std::vector<ShapeDesc> shapes = g.shapes;
  const double grow = g.animate.grow * double(frame);
  if (grow != 0) {
    for (ShapeDesc& s : shapes) {
      s.radius += grow;
      s.scale += grow;
      s.min = s.min - Vec3d{grow, grow, grow};
      s.max = s.max + Vec3d{grow, grow, grow};
    }
  }
  CheckShapes(g, shapes,
              "grid '" + g.name + "'" + (grow != 0 ? " at frame " + std::to_string(frame) : ""));
  return shapes;
}

void ValidateSceneDescription(const SceneDescription& d, const std::string& what) {
  if (d.grids.empty()) {
    throw InputError(what + ": the scene has no grid (add a [[grid]] with a file or shapes)");
  }
  if (d.name.empty() || d.name.find('%') != std::string::npos) {
    throw InputError(what + ": name '" + d.name + "' must be non-empty without '%'");
  }
  std::set<std::string> names;
  for (const GridDesc& g : d.grids) {
    const std::string gw = what + ": grid '" + g.name + "'";
    if (!names.insert(g.name).second) throw InputError(gw + " is defined twice");
    if (!g.from_file()) {
      try {
        ShapesAtFrame(g, 0);
      } catch (const InputError& e) {
        throw InputError(what + ": " + e.what());
      }
    }
    if (g.from_file() && g.animate.grow != 0) throw InputError(gw + ": a file's grid cannot grow");
    if (g.noise.on && !g.fog) throw InputError(gw + ": noise needs role = \"fog\"");
    if (!(g.scale > 0) || !std::isfinite(g.scale))
      throw InputError(gw + ": scale must be positive");
    if (g.degrees != 0 && !(Length(g.axis) > 0)) throw InputError(gw + ": rotate axis is zero");
    if (!g.fog) CheckSurfaceMaterial(g.surface_material, gw);
  }
  for (std::size_t i = 0; i < d.lights.size(); ++i) {
    ValidateLight(d.lights[i], what + ": light " + std::to_string(i + 1));
  }
  if (!d.frames.empty()) ParseFrameRange(d.frames, what + ": frames");
}

SceneDescription ParseSceneDescription(std::string_view text, const std::string& source,
                                       const std::string& dir) {
  toml::table root;
  try {
    root = toml::parse(text, source);
  } catch (const toml::parse_error& e) {
    throw InputError(TomlWhere(source, e.source()) + ": " + std::string(e.description()));
  }
  SceneDescription d;
  Table s(root, "", source);
  d.name = s.String("name", source);
  if (const toml::node* f = s.Get("frames")) {
    d.frames = s.String("frames", "");
    try {
      d.frames = FormatFrameRange(ParseFrameRange(d.frames, "frames").front(),
                                  ParseFrameRange(d.frames, "frames").back());
    } catch (const InputError& e) {
      s.Fail(*f, "frames", std::string(e.what()) + " (expected \"A..B\")");
    }
  }
  if (const toml::table* sky = s.SubTable("sky")) {
    Table st(*sky, "sky.", source);
    d.sky_top = st.Color("top", d.sky_top, 1e6);
    d.sky_bottom = st.Color("bottom", d.sky_bottom, 1e6);
    st.ReportUnused();
  }
  if (const toml::table* cam = s.SubTable("camera")) ReadCamera(*cam, d, source);
  const auto lights = s.Tables("light");
  for (std::size_t i = 0; i < lights.size(); ++i) {
    d.lights.push_back(ReadLight(*lights[i], i, source));
  }
  if (d.lights.empty()) d.lights.push_back(Light{});  // vdb_render's default light
  const auto grids = s.Tables("grid");
  for (std::size_t i = 0; i < grids.size(); ++i) {
    d.grids.push_back(ReadGrid(*grids[i], i, source, dir));
  }
  s.ReportUnused();
  ValidateSceneDescription(d, source);
  return d;
}

SceneDescription LoadSceneDescription(const std::string& source) {
  if (source == "builtin") return ParseSceneDescription(BuiltinSceneText(), "builtin", ".");
  std::string text;
  if (std::filesystem::is_directory(source) || !ReadFile(source, &text)) {
    throw InputError("--scene " + source + ": cannot read the scene file");
  }
  const std::string dir = std::filesystem::path(source).parent_path().string();
  return ParseSceneDescription(text, source, dir.empty() ? "." : dir);
}

std::string PrintSceneDescription(const SceneDescription& d) {
  std::ostringstream o;
  o << "# The resolved scene (raycell record --print-scene): every value written.\n";
  o << "name = " << Quote(d.name) << "\n";
  if (!d.frames.empty()) o << "frames = " << Quote(d.frames) << "\n";
  o << "\n[sky]\ntop = " << Col(d.sky_top) << "\nbottom = " << Col(d.sky_bottom) << "\n";
  const CameraPathSpec& c = d.camera;
  o << "\n[camera]\n";
  if (IsFinite(c.eye)) o << "eye = " << Vec(c.eye) << "\n";
  if (IsFinite(c.target)) o << "target = " << Vec(c.target) << "\n";
  o << "up = " << Vec(c.up) << "\nfov = " << Num(c.fov_deg) << "\n";
  if (c.orbit_degrees != 0 || c.orbit_frames != 0) {
    o << "orbit = { degrees = " << Num(c.orbit_degrees);
    if (c.orbit_frames > 0) o << ", frames = " << c.orbit_frames;
    o << " }\n";
  }
  for (const CameraKey& k : c.keys) {
    o << "\n[[camera.key]]\nframe = " << k.frame << "\neye = " << Vec(k.eye)
      << "\ntarget = " << Vec(k.target) << "\nfov = " << Num(k.fov_deg) << "\n";
  }
  for (const Light& l : d.lights) {
    const bool dir = l.type == Light::Type::kDirectional;
    o << "\n[[light]]\ntype = \"" << (dir ? "dir" : "point") << "\"\n"
      << (dir ? "direction" : "position") << " = " << Vec(l.v) << "\ncolor = " << Col(l.color)
      << "\n";
  }
  for (const GridDesc& g : d.grids) {
    o << "\n[[grid]]\nname = " << Quote(g.name) << "\nrole = \"" << (g.fog ? "fog" : "surface")
      << "\"\n";
    if (g.from_file()) {
      o << "file = " << Quote(g.file) << "\n";
      if (!g.vdb_grid.empty()) o << "grid = " << Quote(g.vdb_grid) << "\n";
    } else {
      o << "voxel = " << Num(g.voxel) << "\nband = " << Num(g.band) << "\n";
    }
    if (g.fog) o << "ramp = " << Num(g.ramp) << "\n";
    o << "scale = " << Num(g.scale) << "\ntranslate = " << Vec(g.translate) << "\n";
    o << "rotate = { axis = " << Vec(g.axis) << ", degrees = " << Num(g.degrees) << " }\n";
    if (g.fog) {
      const FogMaterial& m = g.fog_material;
      o << "material = { absorb = " << Col(m.absorption) << ", scatter = " << Col(m.scattering)
        << ", gain = " << Num(m.shadow_gain) << " }\n";
    } else {
      const SurfaceMaterial& m = g.surface_material;
      o << "material = { color = " << Col(m.color) << ", reflect = " << Num(m.reflectivity)
        << ", transparency = " << Num(m.transparency) << ", ior = " << Num(m.ior) << " }\n";
    }
    if (g.noise.on) {
      const NoiseDesc& n = g.noise;
      o << "noise = { seed = " << n.seed << ", period = " << n.period << ", octaves = " << n.octaves
        << ", amount = " << Num(n.amount) << ", threshold = " << Num(n.threshold) << " }\n";
    }
    if (g.animate.any()) {
      o << "animate = { translate = " << Vec(g.animate.translate)
        << ", rotate = " << Num(g.animate.rotate);
      if (!g.from_file()) o << ", grow = " << Num(g.animate.grow);
      o << " }\n";
    }
    for (const ShapeDesc& s : g.shapes) {
      o << "\n[[grid.shape]]\ntype = \"" << s.type << "\"\nop = \"" << OpName(s.op) << "\"\n";
      if (s.type == "box") {
        o << "min = " << Vec(s.min) << "\nmax = " << Vec(s.max) << "\n";
      } else {
        o << "center = " << Vec(s.center) << "\n"
          << (s.type == "sphere" ? "radius = " : "scale = ")
          << Num(s.type == "sphere" ? s.radius : s.scale) << "\n";
      }
    }
  }
  return o.str();
}

void ApplyMaterialText(SceneDescription& d, const std::string& text) {
  const auto fields = Split(text, ':');
  const std::string& grid = fields[0];
  const std::string what = "--material '" + text + "'";
  if (fields.size() < 2) throw InputError(what + ": expected GRID:key=value[:key=value...]");
  auto it = std::find_if(d.grids.begin(), d.grids.end(),
                         [&](const GridDesc& g) { return g.name == grid; });
  if (it == d.grids.end()) {
    std::vector<std::string> names;
    for (const GridDesc& g : d.grids) names.push_back(g.name);
    throw InputError(what + ": " + d.name + " has no grid '" + grid +
                     "' (grids: " + Join(names, ", ") + ")");
  }
  ApplyMaterialFields(fields, what, it->fog ? &it->fog_material : nullptr,
                      it->fog ? nullptr : &it->surface_material);
}

void ApplyMaterialFields(const std::vector<std::string>& fields, const std::string& what,
                         FogMaterial* fog, SurfaceMaterial* surface) {
  for (std::size_t i = 1; i < fields.size(); ++i) {
    const auto eq = fields[i].find('=');
    if (eq == std::string::npos) throw InputError(what + ": '" + fields[i] + "' is not key=value");
    const std::string key = fields[i].substr(0, eq), value = fields[i].substr(eq + 1);
    const std::string kwhat = what + " key '" + key + "'";
    const std::vector<double> v = ParseMaterialValues(value, kwhat);
    fog ? SetFogKey(*fog, key, v, kwhat) : SetSurfaceKey(*surface, key, v, kwhat);
  }
  if (surface) CheckSurfaceMaterial(*surface, what);
}

namespace {

std::uint64_t Mix(std::uint64_t z) {  // SplitMix64's finaliser
  z += 0x9e3779b97f4a7c15ull;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

// 16 bits of hash of a lattice point of one octave.
std::uint64_t Lattice(std::uint64_t seed, int octave, std::int64_t x, std::int64_t y,
                      std::int64_t z) {
  std::uint64_t h = Mix(seed ^ Mix(std::uint64_t(octave)));
  h = Mix(h ^ std::uint64_t(x));
  h = Mix(h ^ (std::uint64_t(y) * 0x9e3779b97f4a7c15ull));
  h = Mix(h ^ (std::uint64_t(z) * 0xc2b2ae3d27d4eb4full));
  return h >> 48;
}

std::int64_t FloorDiv(std::int64_t a, std::int64_t b) {
  return a >= 0 ? a / b : -((-a + b - 1) / b);
}

constexpr std::int64_t kQuantum = 4096;  // amount and threshold in steps of 1/4096

}  // namespace

std::uint64_t NoiseDenominator(const NoiseDesc& n) {
  const std::uint64_t p = std::uint64_t(n.period);
  return ((std::uint64_t{1} << n.octaves) - 1) * 65535 * p * p * p;
}

std::uint64_t NoiseNumerator(const NoiseDesc& n, std::int32_t x, std::int32_t y, std::int32_t z) {
  std::uint64_t total = 0;
  for (int k = 0; k < n.octaves; ++k) {
    const std::int64_t p = n.period >> k;
    const std::int64_t cx = FloorDiv(x, p), cy = FloorDiv(y, p), cz = FloorDiv(z, p);
    const std::int64_t r[3] = {x - cx * p, y - cy * p, z - cz * p};
    std::uint64_t sum = 0;  // trilinear: corner values times integer weights, at most 65535 p^3
    for (int c = 0; c < 8; ++c) {
      std::uint64_t w = 1;
      for (int a = 0; a < 3; ++a) w *= std::uint64_t((c >> a) & 1 ? r[a] : p - r[a]);
      sum += w * Lattice(n.seed, k, cx + (c & 1), cy + ((c >> 1) & 1), cz + ((c >> 2) & 1));
    }
    // Octave k weighs 2^(octaves-1-k); its denominator is 65535 (p / 2^k)^3, brought to
    // the first octave's by 8^k.
    total += (std::uint64_t{1} << (n.octaves - 1 - k)) * (sum << (3 * k));
  }
  return total;
}

double NoiseFactor(const NoiseDesc& n, std::int32_t x, std::int32_t y, std::int32_t z) {
  const std::uint64_t num = NoiseNumerator(n, x, y, z), den = NoiseDenominator(n);
  const auto a = std::uint64_t(std::llround(n.amount * kQuantum));
  const auto t = std::uint64_t(std::llround(n.threshold * kQuantum));
  if (num * kQuantum < t * den) return 0;
  // At most 2^12 x 2^48: exact in 64 bits; one rounding into double each, one division.
  return double((kQuantum - a) * den + a * num) / double(kQuantum * den);
}

}  // namespace raycell
