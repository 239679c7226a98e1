// vo_carry --world W.yaml [--world W2.yaml ...] [--rig RIG.yaml] [--config VO.yaml]
//          [--frames N] [--step-m X] [--turn-step-deg X] [--size PX] [--seed N] [--dump FILE.csv]
//
// Drives over rendered worlds (the simulator's renderer and camera models, exact truth),
// runs the VO on them and measures how much of a track's match error carries into its
// next keyframe observation (track carry, rho) and into its own right match (stereo
// carry, rho_s): the sliding window's carry model (window.hpp, track_carry.hpp). Prints
// the estimates per world and pooled; they are what configs/vo.yaml's window_track_carry
// and window_stereo_carry are chosen from.
#include "config/yaml_config.hpp"
#include "vo_carry/track_carry.hpp"
#include "vo_eval/vo_evaluation.hpp"

#include <cstdio>
#include <fstream>
#include <iostream>
#include <stdexcept>
#include <string>
#include <vector>

using namespace rover;

namespace {

const char* kUsage =
    "usage: vo_carry --world W.yaml [--world W2.yaml ...] [--rig RIG.yaml] [--config VO.yaml]\n"
    "                [--frames N] [--step-m X] [--turn-step-deg X] [--size PX] [--seed N]\n"
    "                [--dump FILE.csv]   (one line per observation: its errors against truth)\n";

void Print(const std::string& name, const vo_carry::CarryEstimate& e, const vo_carry::DriveCount* c) {
  std::printf("%-28s", name.c_str());
  if (c) std::printf(" keyframes %3d obs %5d", c->keyframes, c->observations);
  std::printf(" tracks %5d pairs %5d  track_carry %.3f +- %.3f (x %.3f y %.3f; after the image map %.3f, %d pairs)"
              "  stereo_carry %.3f (x %.3f y %.3f)  match sigma %.3f px\n",
              e.tracks, e.track_pairs, e.track_carry, e.track_carry_stderr, e.track_carry_xy.x(), e.track_carry_xy.y(),
              e.track_carry_mapped, e.mapped_pairs,
              e.stereo_carry, e.stereo_carry_xy.x(), e.stereo_carry_xy.y(), e.match_sigma_px);
}

double Number(const std::string& flag, const std::string& text) {
  try {
    std::size_t used = 0;
    const double v = std::stod(text, &used);
    if (used == text.size()) return v;
  } catch (const std::exception&) {
  }
  throw std::invalid_argument(flag + ": expected a number, got '" + text + "'");
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> worlds;
  std::string rig = std::string(ROVER_SOURCE_DIR) + "/configs/cameras/navcam_pinhole.yaml";
  std::string config = std::string(ROVER_SOURCE_DIR) + "/configs/vo.yaml";
  vo_eval::RenderedDriveOptions drive;
  std::string dump_path;
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      if (a == "--help" || a == "-h") {
        std::cout << kUsage
                  << "Measures, against truth on rendered drives, how much of a track's match error carries\n"
                     "into its next keyframe observation and into its right match (window_track_carry,\n"
                     "window_stereo_carry in configs/vo.yaml).\n";
        return 0;
      }
      if (i + 1 >= argc) throw std::invalid_argument("'" + a + "' needs a value (or unknown argument)");
      const std::string v = argv[++i];
      if (a == "--world") worlds.push_back(v);
      else if (a == "--rig") rig = v;
      else if (a == "--config") config = v;
      else if (a == "--dump") dump_path = v;
      else if (a == "--frames") drive.frames = static_cast<int>(Number(a, v));
      else if (a == "--step-m") drive.step_m = Number(a, v);
      else if (a == "--turn-step-deg") drive.turn_step_deg = Number(a, v);
      else if (a == "--size") drive.size = static_cast<int>(Number(a, v));
      else if (a == "--seed") drive.seed = static_cast<std::uint64_t>(Number(a, v));
      else throw std::invalid_argument("unknown argument '" + a + "'");
    }
    if (worlds.empty()) throw std::invalid_argument("give at least one --world WORLD.yaml");
  } catch (const std::exception& e) {
    std::cerr << "vo_carry: " << e.what() << "\n" << kUsage;
    return 2;
  }
  try {
    const vo::VoOptions vo = vo_eval::LoadVoConfig(config);
    drive.rig_path = rig;
    vo_carry::CarryAccumulator all;
    std::ofstream dump;
    if (!dump_path.empty()) {
      dump.open(dump_path);
      if (!dump) throw std::runtime_error(dump_path + ": cannot write the --dump file");
      dump << vo_carry::kDumpHeader << '\n';
    }
    std::printf("rig %s, %d frames of %.2f m, turns up to %.1f deg, seed %llu\n", rig.c_str(), drive.frames,
                drive.step_m, drive.turn_step_deg, static_cast<unsigned long long>(drive.seed));
    for (const std::string& world : worlds) {
      drive.world_path = world;
      const vo_eval::RenderedDriveSequence seq(drive);
      vo_carry::CarryAccumulator acc;
      const vo_carry::DriveCount count = vo_carry::MeasureDrive(seq, vo, &acc, 3.0, dump_path.empty() ? nullptr : &dump);
      Print(seq.world_name(), acc.Estimate(), &count);
      all.Merge(acc);
    }
    Print("pooled", all.Estimate(), nullptr);
  } catch (const std::exception& e) {
    std::cerr << "vo_carry: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
