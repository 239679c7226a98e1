// WorldOptions from YAML. Every key is documented in WORLD_FORMAT.md.
#include "terrain/world.hpp"

#include <cmath>
#include <iomanip>
#include <sstream>
#include <stdexcept>

namespace rover::terrain {

namespace {

using config::ConfigNode;

Eigen::Vector2d Vec2(const ConfigNode& node, const std::string& key, Eigen::Vector2d fallback) {
  std::vector<double> v;
  node.Get(key, v, 2);
  return v.empty() ? fallback : Eigen::Vector2d(v[0], v[1]);
}

Soil ParseSoil(const ConfigNode& node) {
  const std::string word = node.AsString();
  try {
    return SoilFromName(word);
  } catch (const std::invalid_argument&) {
    node.Fail("expected one of: bedrock, packed_soil, sand, got \"" + word + "\"");
  }
}

std::vector<Soil> ParseSoilList(const ConfigNode& node) {
  if (!node.IsSequence()) node.Fail("expected a list of soils (bedrock, packed_soil, sand)");
  std::vector<Soil> soils;
  for (std::size_t i = 0; i < node.size(); ++i) soils.push_back(ParseSoil(node.at(i)));
  return soils;
}

// A region is {circle: {center: [x, y], radius_m: r}} or {polygon: [[x, y], ...]};
// `extra` names other keys allowed beside it (e.g. "soil").
Region ParseRegion(const ConfigNode& node, std::vector<std::string> extra) {
  extra.push_back("circle");
  extra.push_back("polygon");
  node.CheckKeys(extra);
  const bool circle = node.Has("circle"), polygon = node.Has("polygon");
  if (circle == polygon) node.Fail("expected exactly one of circle: or polygon:");
  Region r;
  if (circle) {
    const ConfigNode c = node["circle"];
    c.CheckKeys({"center", "radius_m"});
    r.shape = Region::Shape::kCircle;
    const auto v = c.RequireVector("center", 2);
    r.center = {v[0], v[1]};
    r.radius_m = c.RequireDouble("radius_m", 0.0);
  } else {
    const ConfigNode p = node["polygon"];
    if (!p.IsSequence() || p.size() < 3) p.Fail("expected a list of at least 3 [x, y] points");
    r.shape = Region::Shape::kPolygon;
    for (std::size_t i = 0; i < p.size(); ++i) {
      const auto v = p.at(i).AsVector(2);
      r.vertices.emplace_back(v[0], v[1]);
    }
  }
  return r;
}

void ParseSoilAlbedo(const ConfigNode& node, SoilAlbedo& a) {
  if (node.IsNull()) return;
  node.CheckKeys({"mean", "contrast", "min_wavelength_m", "max_wavelength_m"});
  node.Get("mean", a.mean, 0.01, 0.99);
  node.Get("contrast", a.contrast, 0.0, 2.0);
  node.Get("min_wavelength_m", a.min_wavelength_m, 0.001, 100.0);
  node.Get("max_wavelength_m", a.max_wavelength_m, a.min_wavelength_m, 100.0);
}

}  // namespace

WorldOptions WorldOptions::LoadFile(const std::string& path) {
  return Load(ConfigNode::LoadFile(path));
}

WorldOptions WorldOptions::Load(const ConfigNode& root) {
  WorldOptions o;
  root.CheckKeys({"name", "description", "seed", "map", "base_elevation_m", "slopes", "craters",
                  "roughness", "ripples", "soil", "rocks", "sun", "albedo", "start"});
  root.Get("name", o.name);
  root.Get("seed", o.seed);

  if (root.Has("map")) {
    const ConfigNode m = root["map"];
    m.CheckKeys({"center", "size_m", "resolution_m"});
    o.map_center = Vec2(m, "center", o.map_center);
    o.map_size_m = Vec2(m, "size_m", o.map_size_m);
    if (!(o.map_size_m.x() > 0.0) || !(o.map_size_m.y() > 0.0)) {
      m["size_m"].Fail("expected two sizes > 0 (metres)");
    }
    m.Get("resolution_m", o.resolution_m, 0.005, 1.0);
    // The same count World builds its grids with: refused here, where the file and key are known.
    const double cells = (std::ceil(o.map_size_m.x() / o.resolution_m - 1e-9) + 1.0) *
                         (std::ceil(o.map_size_m.y() / o.resolution_m - 1e-9) + 1.0);
    if (cells > kMaxWorldCells) {
      std::ostringstream os;
      os << "a map of " << o.map_size_m.x() << " x " << o.map_size_m.y() << " m at resolution_m "
         << o.resolution_m << " is " << std::setprecision(3) << cells << " cells (expected at most "
         << static_cast<long long>(kMaxWorldCells)
         << ": a smaller size_m or a coarser resolution_m)";
      m[m.Has("size_m") ? "size_m" : "resolution_m"].Fail(os.str());
    }
  }
  root.Get("base_elevation_m", o.base_elevation_m);

  if (root.Has("slopes")) {
    const ConfigNode list = root["slopes"];
    if (!list.IsSequence()) list.Fail("expected a list of slopes");
    for (std::size_t i = 0; i < list.size(); ++i) {
      const ConfigNode n = list.at(i);
      n.CheckKeys({"angle_deg", "uphill_azimuth_deg", "origin", "from_m", "to_m", "blend_m"});
      SlopeOptions s;
      s.angle_deg = n.RequireDouble("angle_deg", 0.0, 45.0);
      n.Get("uphill_azimuth_deg", s.uphill_azimuth_deg, -360.0, 360.0);
      s.origin = Vec2(n, "origin", s.origin);
      n.Get("from_m", s.from_m);
      n.Get("to_m", s.to_m, s.from_m);
      n.Get("blend_m", s.blend_m, 0.0, 100.0);
      o.slopes.push_back(s);
    }
  }

  if (root.Has("craters")) {
    const ConfigNode list = root["craters"];
    if (!list.IsSequence()) list.Fail("expected a list of craters");
    for (std::size_t i = 0; i < list.size(); ++i) {
      const ConfigNode n = list.at(i);
      n.CheckKeys({"center", "radius_m", "depth_m", "rim_height_m", "rim_width_m"});
      CraterOptions c;
      const auto v = n.RequireVector("center", 2);
      c.center = {v[0], v[1]};
      c.radius_m = n.RequireDouble("radius_m", 0.1, 1000.0);
      c.depth_m = n.RequireDouble("depth_m", 0.0, 100.0);
      c.rim_height_m = 0.1 * c.depth_m;
      c.rim_width_m = 0.25 * c.radius_m;
      n.Get("rim_height_m", c.rim_height_m, 0.0, 100.0);
      n.Get("rim_width_m", c.rim_width_m, 0.0, 1000.0);
      o.craters.push_back(c);
    }
  }

  if (root.Has("roughness")) {
    const ConfigNode n = root["roughness"];
    n.CheckKeys({"amplitude_m", "min_wavelength_m", "max_wavelength_m", "hurst"});
    n.Get("amplitude_m", o.roughness.amplitude_m, 0.0, 10.0);
    n.Get("min_wavelength_m", o.roughness.min_wavelength_m, 0.01, 1000.0);
    n.Get("max_wavelength_m", o.roughness.max_wavelength_m, o.roughness.min_wavelength_m, 1000.0);
    n.Get("hurst", o.roughness.hurst, 0.0, 2.0);
  }

  if (root.Has("ripples")) {
    const ConfigNode n = root["ripples"];
    n.CheckKeys({"amplitude_m", "wavelength_m", "crest_azimuth_deg", "soils"});
    n.Get("amplitude_m", o.ripples.amplitude_m, 0.0, 2.0);
    n.Get("wavelength_m", o.ripples.wavelength_m, 0.05, 100.0);
    n.Get("crest_azimuth_deg", o.ripples.crest_azimuth_deg, -360.0, 360.0);
    if (n.Has("soils")) o.ripples.soils = ParseSoilList(n["soils"]);
  }

  if (root.Has("soil")) {
    const ConfigNode n = root["soil"];
    n.CheckKeys({"default", "patches"});
    if (n.Has("default")) o.default_soil = ParseSoil(n["default"]);
    if (n.Has("patches")) {
      const ConfigNode list = n["patches"];
      if (!list.IsSequence()) list.Fail("expected a list of soil patches");
      for (std::size_t i = 0; i < list.size(); ++i) {
        const ConfigNode p = list.at(i);
        SoilPatch patch;
        patch.region = ParseRegion(p, {"soil"});
        if (!p.Has("soil")) p.Fail("missing key \"soil\" (expected bedrock, packed_soil or sand)");
        patch.soil = ParseSoil(p["soil"]);
        o.soil_patches.push_back(patch);
      }
    }
  }

  if (root.Has("rocks")) {
    const ConfigNode n = root["rocks"];
    n.CheckKeys({"placed", "random"});
    if (n.Has("placed")) {
      const ConfigNode list = n["placed"];
      if (!list.IsSequence()) list.Fail("expected a list of rocks");
      for (std::size_t i = 0; i < list.size(); ++i) {
        const ConfigNode p = list.at(i);
        p.CheckKeys({"name", "position", "diameter_m", "height_m", "keepout", "albedo"});
        Rock r;
        r.name = p.RequireString("name");
        for (const auto& other : o.placed_rocks) {
          if (other.name == r.name) p["name"].Fail("duplicate rock name \"" + r.name + "\"");
        }
        const auto v = p.RequireVector("position", 2);
        r.position = {v[0], v[1]};
        r.diameter_m = p.RequireDouble("diameter_m", 0.01, 20.0);
        r.height_m = 0.5 * r.diameter_m;
        p.Get("height_m", r.height_m, 0.0, 20.0);
        p.Get("keepout", r.keepout);
        p.Get("albedo", r.albedo, 0.01, 0.99);
        r.placed = true;
        o.placed_rocks.push_back(r);
      }
    }
    if (n.Has("random")) {
      const ConfigNode r = n["random"];
      r.CheckKeys({"abundance_k", "min_diameter_m", "max_diameter_m", "height_ratio",
                   "height_spread", "albedo_mean", "albedo_spread", "soils", "exclude"});
      auto& f = o.random_rocks;
      r.Get("abundance_k", f.abundance_k, 0.0, 0.5);
      r.Get("min_diameter_m", f.min_diameter_m, 0.01, 10.0);
      r.Get("max_diameter_m", f.max_diameter_m, f.min_diameter_m, 20.0);
      if (!(f.max_diameter_m > f.min_diameter_m)) {
        r["max_diameter_m"].Fail("expected a diameter > min_diameter_m");
      }
      r.Get("height_ratio", f.height_ratio, 0.0, 2.0);
      r.Get("height_spread", f.height_spread, 0.0, 1.0);
      r.Get("albedo_mean", f.albedo_mean, 0.02, 0.9);
      r.Get("albedo_spread", f.albedo_spread, 0.0, 0.9);
      if (r.Has("soils")) f.soils = ParseSoilList(r["soils"]);
      if (r.Has("exclude")) {
        const ConfigNode list = r["exclude"];
        if (!list.IsSequence()) list.Fail("expected a list of regions");
        for (std::size_t i = 0; i < list.size(); ++i) f.exclude.push_back(ParseRegion(list.at(i), {}));
      }
    }
  }

  if (root.Has("sun")) {
    const ConfigNode n = root["sun"];
    n.CheckKeys({"azimuth_deg", "elevation_deg"});
    n.Get("azimuth_deg", o.sun.azimuth_deg, -360.0, 360.0);
    n.Get("elevation_deg", o.sun.elevation_deg, -90.0, 90.0);
  }

  if (root.Has("albedo")) {
    const ConfigNode n = root["albedo"];
    n.CheckKeys({"bedrock", "packed_soil", "sand", "rock_contrast", "large_scale_contrast"});
    ParseSoilAlbedo(n["bedrock"], o.albedo.bedrock);
    ParseSoilAlbedo(n["packed_soil"], o.albedo.packed_soil);
    ParseSoilAlbedo(n["sand"], o.albedo.sand);
    n.Get("rock_contrast", o.albedo.rock_contrast, 0.0, 2.0);
    n.Get("large_scale_contrast", o.albedo.large_scale_contrast, 0.0, 1.0);
  }

  if (root.Has("start")) {
    const ConfigNode n = root["start"];
    n.CheckKeys({"x", "y", "yaw_deg"});
    n.Get("x", o.start.x);
    n.Get("y", o.start.y);
    n.Get("yaw_deg", o.start.yaw_deg, -360.0, 360.0);
  }
  return o;
}

}  // namespace rover::terrain
