#include "hazard_evaluation.hpp"

#include "avoidance/tops_over_ground.hpp"
#include "geometry/pose.hpp"
#include "render/stereo_renderer.hpp"
#include "traversability/as_grid.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>

namespace rover::hazard_eval {

namespace tv = traversability;

void BandCounts::Add(const BandCounts& o) {
  rocks += o.rocks;
  rocks_detected += o.rocks_detected;
  in_view_cells += o.in_view_cells;
  unknown_cells += o.unknown_cells;
  traversable_cells += o.traversable_cells;
  false_unsafe_cells += o.false_unsafe_cells;
  unsafe_cells += o.unsafe_cells;
  unsafe_found_cells += o.unsafe_found_cells;
  crest_cells += o.crest_cells;
  crest_truly_unsafe += o.crest_truly_unsafe;
  tall_cells += o.tall_cells;
  tall_read_low += o.tall_read_low;
  top_rocks_detected += o.top_rocks_detected;
  top_false_unsafe_cells += o.top_false_unsafe_cells;
  top_unsafe_found_cells += o.top_unsafe_found_cells;
  tall_step_error_sum += o.tall_step_error_sum;
}

BandCounts EvalResult::Within4m() const {
  BandCounts b = bands[0];
  b.Add(bands[1]);
  return b;
}

namespace {

// The rover's pose standing on the ground at (x, y) facing yaw: attitude from the normal.
Eigen::Isometry3d PoseOnGround(const terrain::World& world, double x, double y, double yaw) {
  const Eigen::Vector3d n = world.NormalUp(x, y);
  const Eigen::Matrix3d Rz = geometry::RotationFromRpy(0, 0, yaw);
  const Eigen::Vector3d n_yawed = Rz.transpose() * n;
  const double pitch = std::atan2(-n_yawed.x(), -n_yawed.z());
  const double roll = std::atan2(n_yawed.y(), std::hypot(n_yawed.x(), n_yawed.z()));
  return geometry::PoseFromXyzRpy(x, y, -world.Elevation(x, y), roll, pitch, yaw);
}

int Band(double range_m) {
  if (range_m < 0 || range_m >= 6.0) return -1;
  return static_cast<int>(range_m / 2.0);
}

// In both images (the stereo overlap).
bool InView(const geometry::StereoRig& rig, const Eigen::Isometry3d& T_rover_site,
            const Eigen::Vector3d& p_site) {
  for (const auto* cam : {rig.left.get(), rig.right.get()}) {
    Eigen::Vector2d px;
    if (!cam->Project(T_rover_site * p_site, &px)) return false;
    if (!(px.x() >= 0 && px.y() >= 0 && px.x() <= cam->width() - 1 && px.y() <= cam->height() - 1))
      return false;
  }
  return true;
}

// In both HAZCAM images, within its stereo range and in front of the body (min_x_m).
bool InHazcamView(const geometry::StereoRig& rig, const tv::MapOptions& stereo, const Eigen::Isometry3d& T_rover_site,
                  const Eigen::Vector3d& p_site) {
  const Eigen::Vector3d p = T_rover_site * p_site;
  if (p.x() < stereo.min_x_m || std::hypot(p.x(), p.y()) > stereo.max_range_m) return false;
  return InView(rig, T_rover_site, p_site);
}

// Cells this tall or more in truth, and a reading this much under the truth: how the map
// reads steps near the limit (the table's "steps of cells ..." line).
constexpr float kTallStepM = 0.15f, kReadLowM = 0.08f;

// The cells the top rule (EvalOptions::top_rise_m) makes unsafe on the map as the vote sees
// it (traversability::AsGrid): 1 where it marked a cell; empty when off.
std::vector<char> TopMarked(const tv::TraversabilityMap& map, const EvalOptions& options) {
  if (options.top_rise_m <= 0) return {};
  const avoidance::Grid plain = tv::AsGrid(map);
  avoidance::Grid g = plain;
  avoidance::MarkTopsOverGround(&g, options.top_ground_radius_m, options.top_rise_m);
  std::vector<char> marked(g.state.size(), 0);
  for (std::size_t k = 0; k < marked.size(); ++k)
    marked[k] = g.state[k] == avoidance::CellClass::kUnsafe && plain.state[k] != avoidance::CellClass::kUnsafe;
  return marked;
}

bool Marked(const std::vector<char>& marked, std::size_t idx) { return !marked.empty() && marked[idx]; }

}  // namespace

// 5x5 samples a cell (FillTruth in hazard_evaluation.hpp).
void FillTruth(const terrain::World& world, bool at_mean, tv::TraversabilityMap* truth) {
  truth->Clear();
  const int k = 5;
  const double cell = truth->cell_size();
  std::vector<Eigen::Vector3d> pts;
  pts.reserve(static_cast<std::size_t>(truth->rows()) * truth->cols() * 3);
  for (int i = 0; i < truth->rows(); ++i)
    for (int j = 0; j < truth->cols(); ++j) {
      double top = -1e9, sum = 0;
      for (int a = 0; a < k; ++a)
        for (int b = 0; b < k; ++b) {
          const double e = world.ElevationDetailed(truth->origin_x() + (i + (a + 0.5) / k) * cell,
                                                   truth->origin_y() + (j + (b + 0.5) / k) * cell);
          top = std::max(top, e);
          sum += e;
        }
      if (at_mean) top = sum / (k * k);
      // min_points copies at the cell centre.
      const Eigen::Vector3d p(truth->origin_x() + (i + 0.5) * cell, truth->origin_y() + (j + 0.5) * cell, -top);
      for (int c = 0; c < truth->options().min_points; ++c) pts.push_back(p);
    }
  truth->AddPoints(pts, std::vector<double>(pts.size(), 0.005));
}

EvalResult Evaluate(const terrain::World& world, const geometry::StereoRig& rig_full,
                    const EvalOptions& options) {
  if (options.poses.empty()) throw std::invalid_argument("hazard-eval: no poses to evaluate");
  if (!rig_full.left || !rig_full.right) throw std::invalid_argument("hazard-eval: the rig has no models");
  render::RenderOptions ro = options.render;
  ro.image_scale = static_cast<double>(options.image_size) / rig_full.left->width();
  render::StereoRenderer renderer(ro);
  // The HAZCAM pair as camera_capture renders it (capture::RenderedCameras): its own scale,
  // and the shadow of the mast that carries the main rig.
  const bool hazcam = static_cast<bool>(options.hazcam_rig.left);
  render::RenderOptions rh = options.render;
  if (hazcam) {
    rh.image_scale = static_cast<double>(options.hazcam_image_size) / options.hazcam_rig.left->width();
    rh.rover_shadow = render::MastUnderRig(rh.rover_shadow, rig_full);
  }
  render::StereoRenderer hazcam_renderer(rh);
  tv::TraversabilityMap map(options.map);
  // The truth is the exact surface, every crest in it: no view to judge (crest_view_range_m).
  tv::MapOptions truth_options = options.map;
  truth_options.crest_view_range_m = 0.0;
  tv::TraversabilityMap truth(truth_options);
  geometry::Matrix6d cov = geometry::Matrix6d::Zero();
  const double sp = options.pose_sigma_m, sa = options.pose_sigma_deg * M_PI / 180.0;
  cov.diagonal() << sp * sp, sp * sp, sp * sp, sa * sa, sa * sa, sa * sa;

  EvalResult result;
  for (std::size_t k = 0; k < options.poses.size(); ++k) {
    const EvalPose& ep = options.poses[k];
    if (!world.Contains(ep.x, ep.y)) {
      std::ostringstream s;
      s << "hazard-eval: pose " << k + 1 << " (" << ep.x << ", " << ep.y << ") is off the world's map";
      throw std::invalid_argument(s.str());
    }
    const Eigen::Isometry3d T =
        options.fixed_attitude
            ? geometry::PoseFromXyzRpy(ep.x, ep.y, -world.Elevation(ep.x, ep.y), options.roll_deg * M_PI / 180.0,
                                       options.pitch_deg * M_PI / 180.0, ep.yaw_deg * M_PI / 180.0)
            : PoseOnGround(world, ep.x, ep.y, ep.yaw_deg * M_PI / 180.0);
    const render::StereoImages images =
        renderer.RenderPair(world, rig_full, T, options.first_frame_seed + static_cast<std::int64_t>(k));
    map.Recentre(ep.x, ep.y);
    std::array<double, 6> pe = options.pose_error;
    for (int e = 0; e < 6; ++e) pe[e] += ep.error[e];
    const double deg = M_PI / 180.0;
    const Eigen::Isometry3d T_map =
        geometry::PoseFromXyzRpy(pe[0], pe[1], pe[2], 0, 0, 0) * T * geometry::PoseFromXyzRpy(0, 0, 0, pe[3] * deg, pe[4] * deg, pe[5] * deg);
    render::StereoImages hazcam_images;
    if (hazcam) {
      hazcam_images = hazcam_renderer.RenderPair(world, options.hazcam_rig, T, options.first_frame_seed + static_cast<std::int64_t>(k));
      map.AddStereoPair(hazcam_images.left, hazcam_images.right, hazcam_images.rig, T_map, cov, &options.hazcam_map);
    }
    const auto t0 = std::chrono::steady_clock::now();
    map.AddStereoPair(images.left, images.right, images.rig, T_map, cov);
    map.cells();  // the rating is part of the update
    result.update_seconds.push_back(
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());

    truth.Recentre(ep.x, ep.y);
    FillTruth(world, options.truth_at_cell_mean, &truth);
    const Eigen::Isometry3d T_rover_site = T.inverse();
    const auto& mc = map.cells();
    const auto& tc = truth.cells();
    const std::vector<char> top_marked = TopMarked(map, options);
    for (int i = 0; i < map.rows(); ++i) {
      for (int j = 0; j < map.cols(); ++j) {
        const double x = map.origin_x() + (i + 0.5) * map.cell_size();
        const double y = map.origin_y() + (j + 0.5) * map.cell_size();
        const int band = Band(std::hypot(x - ep.x, y - ep.y));
        if (band < 0) continue;
        const Eigen::Vector3d ground(x, y, -world.Elevation(x, y));
        const std::size_t idx = static_cast<std::size_t>(i) * map.cols() + j;
        const double range = std::hypot(x - ep.x, y - ep.y);
        // Rated cells, and those unknown only by an unseen crest (crest_view_range_m).
        if (range < options.dump_range_m && (mc[idx].state != tv::CellState::kUnknown || mc[idx].crest_unseen))
          result.dumped.push_back({static_cast<int>(k) + 1, x, y, range, mc[idx], tc[idx]});
        if (!InView(images.rig, T_rover_site, ground) &&
            !(hazcam && InHazcamView(hazcam_images.rig, options.hazcam_map, T_rover_site, ground)))
          continue;
        BandCounts& b = result.bands[band];
        ++b.in_view_cells;
        if (mc[idx].state == tv::CellState::kUnknown) ++b.unknown_cells;
        if (mc[idx].crest_unseen) {
          ++b.crest_cells;
          b.crest_truly_unsafe += tc[idx].state == tv::CellState::kUnsafe;
        }
        if (mc[idx].state != tv::CellState::kUnknown && mc[idx].height_sigma_m >= 0 &&
            tc[idx].state != tv::CellState::kUnknown && tc[idx].step_m >= kTallStepM) {
          ++b.tall_cells;
          b.tall_step_error_sum += mc[idx].step_m - tc[idx].step_m;
          b.tall_read_low += mc[idx].step_m <= tc[idx].step_m - kReadLowM;
        }
        if (tc[idx].state == tv::CellState::kUnsafe) {
          ++b.unsafe_cells;
          if (mc[idx].state == tv::CellState::kUnsafe) ++b.unsafe_found_cells;
          b.top_unsafe_found_cells += Marked(top_marked, idx);
        }
        if (tc[idx].state != tv::CellState::kUnknown && tc[idx].state != tv::CellState::kUnsafe) {
          ++b.traversable_cells;
          b.top_false_unsafe_cells += Marked(top_marked, idx);
          if (mc[idx].state == tv::CellState::kUnsafe) {
            ++b.false_unsafe_cells;
            result.false_unsafe.push_back({static_cast<int>(k) + 1, x, y,
                                           std::hypot(x - ep.x, y - ep.y), mc[idx], tc[idx]});
          }
        }
      }
    }
    for (const terrain::Rock& rock : world.rocks()) {
      if (rock.height_m <= options.rock_limit_m) continue;
      const double range = std::hypot(rock.position.x() - ep.x, rock.position.y() - ep.y);
      const int band = Band(range);
      if (band < 0) continue;
      const Eigen::Vector3d top(rock.position.x(), rock.position.y(),
                                -world.Elevation(rock.position.x(), rock.position.y()));
      if (!InView(images.rig, T_rover_site, top) &&
          !(hazcam && InHazcamView(hazcam_images.rig, options.hazcam_map, T_rover_site, top)))
        continue;
      const tv::Cell c = map.At(rock.position.x(), rock.position.y());
      RockSighting s;
      s.name = rock.name;
      s.pose = static_cast<int>(k) + 1;
      s.range_m = range;
      s.height_m = rock.height_m;
      s.detected = c.state == tv::CellState::kUnsafe;
      const int ri = static_cast<int>(std::floor((rock.position.x() - map.origin_x()) / map.cell_size()));
      const int rj = static_cast<int>(std::floor((rock.position.y() - map.origin_y()) / map.cell_size()));
      s.detected_by_top = !s.detected && ri >= 0 && rj >= 0 && ri < map.rows() && rj < map.cols() &&
                          Marked(top_marked, static_cast<std::size_t>(ri) * map.cols() + rj);
      s.step_m = c.step_m;
      s.state = tv::CellStateName(c.state);
      result.sightings.push_back(s);
      ++result.bands[band].rocks;
      if (s.detected) ++result.bands[band].rocks_detected;
      if (s.detected_by_top) ++result.bands[band].top_rocks_detected;
    }
  }
  std::vector<double> t = result.update_seconds;
  std::sort(t.begin(), t.end());
  result.median_update_seconds = t[t.size() / 2];
  return result;
}

std::string FormatTable(const EvalResult& r, double rock_limit_m, double top_rise_m) {
  auto pct = [](int num, int den) {
    char buf[32];
    if (den == 0) std::snprintf(buf, sizeof buf, "%6s", "-");
    else std::snprintf(buf, sizeof buf, "%5.1f%%", 100.0 * num / den);
    return std::string(buf);
  };
  std::ostringstream out;
  char line[256];
  std::snprintf(line, sizeof line, "%-7s | %6s %8s %7s | %11s %12s %7s | %7s %8s %7s\n", "range",
                "rocks", "detected", "", "traversable", "false unsafe", "", "in view",
                "unknown", "");
  out << line;
  char limit[32];
  std::snprintf(limit, sizeof limit, ">%.2fm", rock_limit_m);
  std::snprintf(line, sizeof line, "%-7s | %6s %8s %7s | %11s %12s %7s | %7s %8s %7s\n", "",
                limit, "", "", "cells",
                "cells", "", "cells", "cells", "");
  out << line;
  out << std::string(93, '-') << "\n";
  const char* names[] = {"0-2 m", "2-4 m", "4-6 m"};
  auto row = [&](const char* name, const BandCounts& b) {
    std::snprintf(line, sizeof line, "%-7s | %6d %8d %7s | %11d %12d %7s | %7d %8d %7s\n", name,
                  b.rocks, b.rocks_detected, pct(b.rocks_detected, b.rocks).c_str(),
                  b.traversable_cells, b.false_unsafe_cells,
                  pct(b.false_unsafe_cells, b.traversable_cells).c_str(), b.in_view_cells,
                  b.unknown_cells, pct(b.unknown_cells, b.in_view_cells).c_str());
    out << line;
  };
  for (int k = 0; k < EvalResult::kBands; ++k) row(names[k], r.bands[k]);
  out << std::string(93, '-') << "\n";
  row("0-4 m", r.Within4m());
  const BandCounts near = r.Within4m();
  std::snprintf(line, sizeof line, "unsafe cells in truth (in view, 0-4 m): %d, marked unsafe by the map: %d %s\n",
                near.unsafe_cells, near.unsafe_found_cells,
                pct(near.unsafe_found_cells, near.unsafe_cells).c_str());
  out << line;
  if (near.tall_cells > 0) {
    std::snprintf(line, sizeof line,
                  "steps of cells %.2f m or more in truth, rated by both (0-4 m): %d, map less truth %+.3f m on "
                  "average, %d %s read %.2f m or more low\n",
                  kTallStepM, near.tall_cells, near.tall_step_error_sum / near.tall_cells, near.tall_read_low,
                  pct(near.tall_read_low, near.tall_cells).c_str(), kReadLowM);
    out << line;
  }
  if (top_rise_m > 0) {
    std::snprintf(line, sizeof line,
                  "the vote's top rule at %.2f m (0-4 m): rocks the map missed found %d of %d; cells it makes "
                  "unsafe: %d unsafe in truth, %d traversable %s\n",
                  top_rise_m, near.top_rocks_detected, near.rocks - near.rocks_detected, near.top_unsafe_found_cells,
                  near.top_false_unsafe_cells, pct(near.top_false_unsafe_cells, near.traversable_cells).c_str());
    out << line;
  }
  if (near.crest_cells > 0) {
    std::snprintf(line, sizeof line, "cells read at the step limit for an unseen crest (0-4 m): %d, unsafe in truth: %d %s\n",
                  near.crest_cells, near.crest_truly_unsafe, pct(near.crest_truly_unsafe, near.crest_cells).c_str());
    out << line;
  }
  return out.str();
}

}  // namespace rover::hazard_eval
