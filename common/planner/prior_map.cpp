#include "planner/prior_map.hpp"

#include "config/yaml_config.hpp"

#include <cmath>
#include <map>

namespace rover::planner {

namespace {

PriorCostMap Load(const config::ConfigNode& root) {
  root.CheckKeys({"prior_cost_map"});
  const config::ConfigNode n = root["prior_cost_map"];
  if (n.IsNull() || !n.IsMap()) root.Fail("expected a map `prior_cost_map` with south_west, cell_m, legend, rows");
  n.CheckKeys({"south_west", "cell_m", "legend", "rows"});
  PriorCostMap m;
  const std::vector<double> sw = n.RequireVector("south_west", 2);
  m.cell_m = n.RequireDouble("cell_m", 1e-3, 1e3);
  const config::ConfigNode legend = n["legend"];
  if (legend.IsNull() || !legend.IsMap()) n.Fail("legend: expected a map of one character to a cost >= 1 or impassable");
  std::map<char, double> cost_of;
  for (const std::string& key : legend.Keys()) {
    if (key.size() != 1) legend[key].Fail("expected a key of one character");
    const config::ConfigNode v = legend[key];
    if (v.yaml().IsScalar() && v.yaml().as<std::string>() == "impassable") {
      cost_of[key[0]] = PriorCostMap::kImpassable;
    } else {
      cost_of[key[0]] = v.AsDouble(1.0, 1e6);
    }
  }
  const config::ConfigNode rows = n["rows"];
  if (rows.IsNull() || !rows.IsSequence() || rows.size() == 0) n.Fail("rows: expected a non-empty list of strings");
  m.rows = static_cast<int>(rows.size());
  m.cols = static_cast<int>(rows.at(0).AsString().size());
  if (m.cols == 0) rows.at(0).Fail("expected a non-empty string");
  m.cost.assign(static_cast<std::size_t>(m.rows) * m.cols, 1.0);
  for (int r = 0; r < m.rows; ++r) {
    const std::string line = rows.at(static_cast<std::size_t>(r)).AsString();
    if (static_cast<int>(line.size()) != m.cols)
      rows.at(static_cast<std::size_t>(r)).Fail("expected " + std::to_string(m.cols) + " characters like the first row, got " +
                                                std::to_string(line.size()));
    const int i = m.rows - 1 - r;  // the first row is the northern edge
    for (int j = 0; j < m.cols; ++j) {
      const auto it = cost_of.find(line[static_cast<std::size_t>(j)]);
      if (it == cost_of.end())
        rows.at(static_cast<std::size_t>(r)).Fail(std::string("character '") + line[static_cast<std::size_t>(j)] +
                                                  "' is not in the legend");
      m.cost[static_cast<std::size_t>(i) * m.cols + j] = it->second;
    }
  }
  m.origin_x = sw[0];
  m.origin_y = sw[1];
  return m;
}

}  // namespace

double PriorCostMap::CostAt(double x, double y) const {
  const int i = static_cast<int>(std::floor((x - origin_x) / cell_m));
  const int j = static_cast<int>(std::floor((y - origin_y) / cell_m));
  if (i < 0 || j < 0 || i >= rows || j >= cols) return 1.0;
  return cost[static_cast<std::size_t>(i) * cols + j];
}

PriorCostMap PriorCostMap::LoadFile(const std::string& path) { return Load(config::ConfigNode::LoadFile(path)); }

PriorCostMap PriorCostMap::FromYaml(const std::string& text, const std::string& source_name) {
  return Load(config::ConfigNode::FromString(text, source_name));
}

}  // namespace rover::planner
