#include "fault_inject/packets.hpp"

#include "fault_inject/lcm_schema.hpp"
#include "imaging/hostile_png.hpp"

#include <rover_msgs/capture_request_t.hpp>
#include <rover_msgs/hazard_query_t.hpp>
#include <rover_msgs/hazard_reply_t.hpp>
#include <rover_msgs/hazard_status_t.hpp>
#include <rover_msgs/heartbeat_t.hpp>
#include <rover_msgs/imu_t.hpp>
#include <rover_msgs/keepout_zones_t.hpp>
#include <rover_msgs/traversability_map_t.hpp>
#include <rover_msgs/mobility_command_t.hpp>
#include <rover_msgs/mobility_status_t.hpp>
#include <rover_msgs/new_site_t.hpp>
#include <rover_msgs/pose_t.hpp>
#include <rover_msgs/rover_clock_t.hpp>
#include <rover_msgs/sequence_control_t.hpp>
#include <rover_msgs/sequence_status_t.hpp>
#include <rover_msgs/sequence_submit_t.hpp>
#include <rover_msgs/sim_truth_t.hpp>
#include <rover_msgs/step_report_t.hpp>
#include <rover_msgs/stereo_frame_t.hpp>
#include <rover_msgs/vo_update_t.hpp>
#include <rover_msgs/wheel_odometry_t.hpp>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <mutex>
#include <random>
#include <stdexcept>

namespace rover::fault {
namespace {

// Ids far from anything a real run uses, so no receiver mistakes a sample for its own.
constexpr std::int64_t kFakeId = 900000;

template <class Msg>
Bytes Encode(const Msg& m) {
  Bytes b(static_cast<std::size_t>(m.getEncodedSize()));
  if (m.encode(b.data(), 0, static_cast<int>(b.size())) < 0) {
    throw std::runtime_error(std::string("cannot encode a sample ") + Msg::getTypeName());
  }
  return b;
}

std::int64_t PubSeq(std::uint32_t count) {
  return static_cast<std::int64_t>((static_cast<std::uint64_t>(InjectorPublisherId()) << 32) | count);
}

void Identity(double q[4]) {
  q[0] = 1;
  q[1] = q[2] = q[3] = 0;
}

void Diagonal(double c[6][6], double v) {
  for (int r = 0; r < 6; ++r)
    for (int k = 0; k < 6; ++k) c[r][k] = r == k ? v : 0.0;
}

rover_msgs::pose_t SamplePose(std::int64_t now) {
  rover_msgs::pose_t m{};
  m.utime = now;
  m.pub_seq = PubSeq(1);
  Identity(m.orientation);
  Diagonal(m.covariance, 1e-4);
  m.source = rover_msgs::pose_t::SOURCE_WHEEL_IMU;
  m.last_vo_to_frame = -1;
  return m;
}

// ---- images ----

Bytes EncodePng(const cv::Mat& image) {
  Bytes png;
  if (!cv::imencode(".png", image, png)) throw std::runtime_error("cannot encode a sample PNG");
  return png;
}

// A textured gray image (VO would find corners in it).
cv::Mat Texture(int w, int h, std::uint32_t seed) {
  cv::Mat m(h, w, CV_8UC1);
  cv::RNG rng(seed);
  rng.fill(m, cv::RNG::UNIFORM, 0, 256);
  return m;
}

// Rewrites a PNG's IHDR size; with `fix_crc` the CRC too, so only a size check rejects it.
Bytes PatchIhdr(Bytes png, std::uint32_t w, std::uint32_t h, bool fix_crc) {
  imaging::PatchPngHeader(png, w, h, -1, fix_crc);
  return png;
}

// A PNG bomb (imaging::PngBomb), built once per shape: deflating hundreds of MB takes a
// second.
const Bytes& PngBomb(std::uint32_t header_w, std::uint32_t header_h, int rows, int cols) {
  static std::mutex mutex;
  static std::map<std::tuple<std::uint32_t, std::uint32_t, int, int>, Bytes> cache;
  std::lock_guard<std::mutex> lock(mutex);
  Bytes& png = cache[{header_w, header_h, rows, cols}];
  if (png.empty()) png = imaging::PngBomb(header_w, header_h, rows, cols);
  return png;
}

constexpr int kW = 64, kH = 48;

rover_msgs::camera_model_t PinholeModel(int w, int h, double baseline_m) {
  rover_msgs::camera_model_t m{};
  m.type = "pinhole";
  m.width = w;
  m.height = h;
  // fx fy cx cy tx ty tz qw qx qy qz (geometry::PinholeCamera::Params)
  m.params = {50.0, 50.0, 0.5 * (w - 1), 0.5 * (h - 1), baseline_m, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0};
  m.num_params = static_cast<std::int32_t>(m.params.size());
  return m;
}

void SetData(rover_msgs::image_t& img, Bytes data) {
  img.data = std::move(data);
  img.size = static_cast<std::int32_t>(img.data.size());
}

rover_msgs::image_t PngImage(int w, int h, std::uint32_t seed) {
  rover_msgs::image_t img{};
  img.width = w;
  img.height = h;
  img.encoding = rover_msgs::image_t::ENCODING_PNG;
  SetData(img, EncodePng(Texture(w, h, seed)));
  return img;
}

rover_msgs::stereo_frame_t SampleFrame(std::int64_t now, std::int64_t frame_id) {
  rover_msgs::stereo_frame_t f{};
  f.utime = now;
  f.pub_seq = PubSeq(1);
  f.frame_id = frame_id;
  f.purpose = "vo";
  f.left = PngImage(kW, kH, 1);
  f.right = PngImage(kW, kH, 2);
  f.left_model = PinholeModel(kW, kH, 0.0);
  f.right_model = PinholeModel(kW, kH, 0.2);
  f.pose_at_capture = SamplePose(now);
  f.left_utime = f.right_utime = now;
  return f;
}

// ---- samples: one valid message per channel ----

Bytes Sample(const std::string& channel, std::int64_t now) {
  using namespace rover_msgs;
  if (channel == "HEARTBEAT") {
    heartbeat_t m{};
    m.utime = now;
    m.process = "fault_inject";
    m.seq = 1;
    m.state = heartbeat_t::STATE_OK;
    m.detail = "injecting faults";
    return Encode(m);
  }
  if (channel == "ROVER_CLOCK") {
    rover_clock_t m{};
    m.utime = now;
    m.pub_seq = PubSeq(1);
    m.rate = 50.0;
    return Encode(m);
  }
  if (channel == "IMU") {
    imu_t m{};
    m.utime = now;
    m.pub_seq = PubSeq(1);
    Identity(m.orientation);
    m.accel[2] = -3.711;
    return Encode(m);
  }
  if (channel == "WHEEL_ODOMETRY") {
    wheel_odometry_t m{};
    m.utime = now;
    m.pub_seq = PubSeq(1);
    m.num_wheels = 6;
    m.wheel_distance_m = {0.1, 0.1, 0.1, 0.1, 0.1, 0.1};
    m.distance_m = 0.1;
    return Encode(m);
  }
  if (channel == "POSE") return Encode(SamplePose(now));
  if (channel == "NEW_SITE") {
    new_site_t m{};
    m.utime = now;
    m.pub_seq = PubSeq(1);
    m.site_index = 1;
    m.auth.sender = "fault_inject";
    return Encode(m);
  }
  if (channel == "MOBILITY_COMMAND") {
    mobility_command_t m{};
    m.utime = now;
    m.pub_seq = PubSeq(1);
    m.command_id = kFakeId;
    m.type = mobility_command_t::TYPE_ARC;
    m.distance_m = 0.05;
    m.auth.sender = "fault_inject";
    return Encode(m);
  }
  if (channel == "MOBILITY_STATUS") {
    mobility_status_t m{};
    m.utime = now;
    m.pub_seq = PubSeq(1);
    m.command_id = kFakeId;
    m.state = mobility_status_t::STATE_IDLE;
    m.detail = "fault_inject";
    return Encode(m);
  }
  if (channel == "CAPTURE_REQUEST") {
    capture_request_t m{};
    m.utime = now;
    m.pub_seq = PubSeq(1);
    m.frame_id = kFakeId;
    m.purpose = "science";
    return Encode(m);
  }
  if (channel == "STEREO_FRAME" || channel == "HAZCAM_FRAME") return Encode(SampleFrame(now, kFakeId));
  if (channel == "VO_UPDATE") {
    vo_update_t m{};
    m.utime = now;
    m.pub_seq = PubSeq(1);
    m.from_frame_id = kFakeId - 1;
    m.to_frame_id = kFakeId;
    m.from_utime = now - 1000000;
    m.to_utime = now;
    m.status = vo_update_t::STATUS_OK;
    m.reason = "fault_inject";
    m.delta_position[0] = 0.01;
    Identity(m.delta_orientation);
    Diagonal(m.covariance, 1e-4);
    return Encode(m);
  }
  if (channel == "KEEPOUT_ZONES") {
    keepout_zones_t m{};
    m.utime = now;
    m.pub_seq = PubSeq(1);
    keepout_zone_t circle{};
    circle.name = "fault_circle";
    circle.shape = keepout_zone_t::SHAPE_CIRCLE;
    circle.center[0] = 100;
    circle.center[1] = 100;
    circle.radius_m = 1;
    keepout_zone_t polygon{};
    polygon.name = "fault_polygon";
    polygon.shape = keepout_zone_t::SHAPE_POLYGON;
    polygon.num_vertices = 3;
    polygon.vertices_x = {100, 101, 100};
    polygon.vertices_y = {-100, -100, -101};
    m.zones = {circle, polygon};
    m.num_zones = 2;
    m.auth.sender = "fault_inject";
    return Encode(m);
  }
  if (channel == "HAZARD_STATUS") {
    hazard_status_t m{};
    m.utime = now;
    m.pub_seq = PubSeq(1);
    m.state = hazard_status_t::STATE_SAFE;
    m.zone_name = "fault_circle";
    m.min_clearance_m = 10;
    m.roll_limit_rad = m.pitch_limit_rad = 0.5;
    m.detail = "fault_inject";
    return Encode(m);
  }
  if (channel == "HAZARD_QUERY") {
    hazard_query_t m{};
    m.utime = now;
    m.pub_seq = PubSeq(1);
    m.query_id = kFakeId;
    m.num_poses = 2;
    m.x = {0.0, 0.1};
    m.y = {0.0, 0.0};
    m.yaw = {0.0, 0.0};
    return Encode(m);
  }
  if (channel == "HAZARD_REPLY") {
    hazard_reply_t m{};
    m.utime = now;
    m.pub_seq = PubSeq(1);
    m.query_id = kFakeId;
    m.verdict = hazard_reply_t::VERDICT_SAFE;
    m.zone_name = "fault_circle";
    m.min_clearance_m = 5;
    m.detail = "fault_inject";
    return Encode(m);
  }
  if (channel == "SEQUENCE_SUBMIT") {
    // A sequence the checker refuses: a copy that slips through must not drive.
    sequence_submit_t m{};
    m.utime = now;
    m.pub_seq = PubSeq(1);
    m.submission_id = kFakeId;
    m.name = "fault_inject.seq";
    m.text = "drive 10 furlongs\n";
    m.auth.sender = "fault_inject";
    return Encode(m);
  }
  if (channel == "SEQUENCE_CONTROL") {
    // RESUME changes nothing while a sequence runs.
    sequence_control_t m{};
    m.utime = now;
    m.pub_seq = PubSeq(1);
    m.action = sequence_control_t::ACTION_RESUME;
    m.reason = "fault_inject";
    m.auth.sender = "fault_inject";
    return Encode(m);
  }
  if (channel == "SEQUENCE_STATUS") {
    sequence_status_t m{};
    m.utime = now;
    m.pub_seq = PubSeq(1);
    m.submission_id = kFakeId;
    m.sequence_name = "fault_inject.seq";
    m.state = sequence_status_t::STATE_RUNNING;
    m.num_commands = 1;
    m.command_text = "drive 1 m";
    m.abort_reason = "";
    m.detail = "fault_inject";
    return Encode(m);
  }
  if (channel == "STEP_REPORT") {
    step_report_t m{};
    m.utime = now;
    m.pub_seq = PubSeq(1);
    m.submission_id = kFakeId;
    m.mobility_command_id = kFakeId;
    m.commanded_distance_m = 0.5;
    m.estimated_distance_m = 0.5;
    m.vo_status = -1;
    m.utime_before = now - 1000000;
    m.utime_after = now;
    return Encode(m);
  }
  if (channel == "SIM_TRUTH") {
    sim_truth_t m{};
    m.utime = now;
    m.pub_seq = PubSeq(1);
    Identity(m.orientation);
    m.soil = "sand";
    m.command_id = -1;
    return Encode(m);
  }
  if (channel == "TRAVERSABILITY_MAP") {
    // A small map far from the rover: safe cells around a tall step.
    traversability_map_t m{};
    m.utime = now;
    m.pub_seq = PubSeq(1);
    m.last_frame_id = kFakeId;
    m.origin_x = 100;
    m.origin_y = 100;
    m.cell_m = 0.2;
    m.rows = 3;
    m.cols = 3;
    m.num_cells = 9;
    m.state.assign(9, traversability_map_t::STATE_SAFE);
    m.state[4] = traversability_map_t::STATE_UNSAFE;
    m.goodness.assign(9, 1.0f);
    m.goodness[4] = 0.0f;
    m.step_m.assign(9, 0.01f);
    m.step_m[4] = 0.5f;
    m.elevation_m.assign(9, 0.0f);
    m.elevation_m[4] = 0.5f;
    m.sigma_m.assign(9, 0.02f);
    m.footprint_length_m = 1.6;
    m.footprint_width_m = 1.2;
    m.max_unknown_fraction = 0.2;
    m.hidden_patch_m = 0.6;
    m.max_scattered_unknown_fraction = 0.5;
    return Encode(m);
  }
  throw std::invalid_argument("no sample for channel " + channel);
}

// ---- groups ----

std::string Number(std::int64_t v) {
  if (v == std::numeric_limits<std::int64_t>::max()) return "INT64_MAX";
  if (v == std::numeric_limits<std::int64_t>::min()) return "INT64_MIN";
  if (v == std::numeric_limits<std::int32_t>::max()) return "2^31-1";
  return std::to_string(v);
}

void PutInt(Bytes& b, const FieldLocation& f, std::int64_t v) {
  if (f.width == 4) PutInt32(b, f.offset, static_cast<std::int32_t>(v));
  else if (f.width == 8) PutInt64(b, f.offset, v);
  else if (f.width == 1) b.at(f.offset) = static_cast<std::uint8_t>(v);
  else throw std::logic_error("field width " + std::to_string(f.width));
}

std::vector<Packet> Malformed(const std::string& channel, const Bytes& base, const Layout& layout,
                              const PacketOptions& o) {
  std::vector<Packet> out;
  auto add = [&](const std::string& what, Bytes bytes) {
    out.push_back({channel, channel + " malformed " + what, std::move(bytes), ""});
  };
  // Every string length and array count: zero, negative, one past the data, huge.
  for (const auto& f : layout.fields) {
    if (f.kind != FieldKind::kStringLength && f.kind != FieldKind::kCount) continue;
    if (f.width != 4 && f.width != 8) continue;
    const auto remaining = static_cast<std::int64_t>(base.size() - f.offset - f.width);
    const char* what = f.kind == FieldKind::kStringLength ? ": string length " : ": count ";
    for (std::int64_t v : {std::int64_t{0}, std::int64_t{-1}, remaining + 1, std::int64_t{50000000},
                           std::int64_t{std::numeric_limits<std::int32_t>::max()}}) {
      Bytes b = base;
      PutInt(b, f, v);
      add(f.path + what + Number(v), std::move(b));
    }
  }
  // Truncated.
  for (std::size_t n : {std::size_t{4}, std::size_t{8}, base.size() / 2, base.size() - 1}) {
    if (n >= base.size()) continue;
    add("truncated to " + std::to_string(n) + " of " + std::to_string(base.size()) + " bytes",
        Bytes(base.begin(), base.begin() + static_cast<long>(n)));
  }
  // Wrong fingerprint; another channel's type.
  Bytes flipped = base;
  flipped[7] ^= 0x5a;
  add("wrong fingerprint", std::move(flipped));
  const auto& all = AllChannels();
  for (std::size_t i = 0; i < all.size(); ++i) {
    if (all[i].channel != channel) continue;
    const auto& other = all[(i + 1) % all.size()];
    add("carrying " + other.channel + "'s " + other.type, Sample(other.channel, o.now_utime));
  }
  // Random bytes behind the right fingerprint.
  std::mt19937 rng(o.seed ^ static_cast<std::uint32_t>(std::hash<std::string>{}(channel)));
  for (std::size_t n : {std::size_t{16}, std::size_t{1000}, std::size_t{60000}, std::size_t{1} << 20}) {
    Bytes b(base.begin(), base.begin() + 8);
    b.resize(8 + n);
    for (std::size_t k = 8; k < b.size(); ++k) b[k] = static_cast<std::uint8_t>(rng());
    add("fingerprint and " + std::to_string(n) + " random bytes", std::move(b));
  }
  // A valid encoding grown past the channel's bound: the first top-level string made
  // longer when there is one (the message still decodes), else bytes after the message.
  if (o.max_payload_bytes) {
    const std::size_t bound = o.max_payload_bytes(channel);
    const std::size_t grow = bound + 1 - std::min(bound, base.size());
    const FieldLocation* text = nullptr;
    for (const auto& f : layout.fields)
      if (f.kind == FieldKind::kStringLength && f.top_level && !text) text = &f;
    Bytes b = base;
    std::string how;
    if (text) {
      const std::int64_t length = GetInt(&b[text->offset], 4);
      PutInt32(b, text->offset, static_cast<std::int32_t>(length + static_cast<std::int64_t>(grow)));
      b.insert(b.begin() + static_cast<long>(text->offset + 4), grow, static_cast<std::uint8_t>('x'));
      how = "its " + text->path + " string";
    } else {
      b.resize(b.size() + grow, 0);
      how = "bytes after the message";
    }
    const std::string what = "oversized: " + std::to_string(b.size()) + " bytes (bound " +
                             std::to_string(bound) + ") by " + how;
    add(what, std::move(b));
  }
  return out;
}

std::vector<Packet> Values(const std::string& channel, const Bytes& base, const Layout& layout) {
  std::vector<Packet> out;
  // The last element of each double field (a check that stops at the first is caught).
  std::map<std::string, std::pair<std::size_t, int>> last;  // path -> offset, element count
  std::vector<std::string> order;
  for (const auto& f : layout.fields) {
    if (f.kind != FieldKind::kDouble) continue;
    auto [it, fresh] = last.try_emplace(f.path, f.offset, 0);
    if (fresh) order.push_back(f.path);
    it->second.first = f.offset;
    ++it->second.second;
  }
  const double inf = std::numeric_limits<double>::infinity();
  for (const auto& path : order) {
    const auto [offset, count] = last[path];
    const std::string element = count > 1 ? path + "[" + std::to_string(count - 1) + "]" : path;
    for (const auto& [name, v] : std::vector<std::pair<std::string, double>>{
             {"NaN", std::numeric_limits<double>::quiet_NaN()}, {"+inf", inf}, {"-inf", -inf}}) {
      Bytes b = base;
      PutDouble(b, offset, v);
      out.push_back({channel, channel + " values " + element + " = " + name, std::move(b), ""});
    }
  }
  for (const auto& f : layout.fields) {
    if (f.kind != FieldKind::kEnum) continue;
    for (std::int64_t v : {99, -1}) {
      Bytes b = base;
      PutInt(b, f, v);
      out.push_back({channel, channel + " values " + f.path + " = " + std::to_string(v) + " (unknown enum)",
                     std::move(b), ""});
    }
  }
  return out;
}

std::vector<Packet> Times(const std::string& channel, const Bytes& base, const Layout& layout,
                          const PacketOptions& o) {
  std::vector<Packet> out;
  const std::int64_t far = 1000000000000;  // 10^12 us: 11.6 days
  for (const auto& f : layout.fields) {
    if (f.kind != FieldKind::kTime) continue;
    for (const auto& [name, v] : std::vector<std::pair<std::string, std::int64_t>>{
             {"now + 1e12 us", o.now_utime + far},
             {"now - 1e12 us", o.now_utime - far},
             {"INT64_MAX", std::numeric_limits<std::int64_t>::max()},
             {"INT64_MIN", std::numeric_limits<std::int64_t>::min()}}) {
      Bytes b = base;
      PutInt64(b, f.offset, v);
      out.push_back({channel, channel + " times " + f.path + " = " + name, std::move(b), ""});
    }
  }
  return out;
}

// `channel`: STEREO_FRAME or HAZCAM_FRAME (one type, the same bad images).
std::vector<Packet> Images(const std::string& channel, const PacketOptions& o) {
  using rover_msgs::image_t;
  std::vector<Packet> out;
  std::int64_t id = kFakeId + 1;
  auto add = [&](const std::string& what, rover_msgs::stereo_frame_t f, std::string expect) {
    f.frame_id = id++;
    out.push_back({channel, channel + " images " + what, Encode(f), std::move(expect)});
  };
  const auto base = SampleFrame(o.now_utime, 0);
  const Bytes good_png = base.left.data;
  const auto side = static_cast<std::uint32_t>(o.bomb_side);

  auto f = base;
  f.left.encoding = image_t::ENCODING_GRAY8;
  f.left.width = -5;
  SetData(f.left, Bytes(5 * kH, 0));
  add("left GRAY8 width -5", f, "expected width and height > 0");
  f.left_model.width = -5;
  add("left GRAY8 width -5, its model too", f, "");
  f = base;
  f.right.width = 0;
  add("right PNG width 0", f, "expected width and height > 0");

  f = base;
  SetData(f.left, PatchIhdr(good_png, 65535, 65535, true));
  add("left PNG header claims 65535x65535", f, "PNG's header says 65535x65535");
  f.left.width = f.left.height = 65535;
  f.left_model.width = f.left_model.height = 65535;
  add("left PNG header claims 65535x65535, declared and modelled so", f, "expected at most");

  const Bytes& bomb = PngBomb(side, side, o.bomb_side, o.bomb_side);
  const std::string bomb_name = "PNG bomb " + std::to_string(side) + "x" + std::to_string(side) + " of zeros (" +
                                std::to_string(bomb.size() / 1024) + " kB)";
  f = base;
  SetData(f.left, bomb);
  add("left " + bomb_name, f, "PNG's header says");
  f.left.width = f.left.height = o.bomb_side;
  f.left_model.width = f.left_model.height = o.bomb_side;
  add("left " + bomb_name + ", declared and modelled so", f, "expected at most");
  f = base;
  SetData(f.left, PngBomb(kW, kH, 4096, 4096));
  add("left PNG with a 64x48 header over 4096x4096 zeros", f, "");  // decodes 48 rows, or refused

  f = base;
  f.left = PngImage(32, 24, 3);
  add("left PNG 32x24 with a 64x48 model", f, "but its camera model is 64x48");
  f = base;
  SetData(f.left, EncodePng(Texture(32, 24, 3)));
  add("left PNG 32x24 declared 64x48", f, "PNG's header says 32x24");
  f = base;
  f.left.width = f.left.height = 65536;
  f.left_model.width = f.left_model.height = 65536;
  f.left.encoding = image_t::ENCODING_GRAY16;
  SetData(f.left, Bytes(16, 0));
  add("left GRAY16 65536x65536 holding 16 bytes", f, "");  // the bus may refuse the model
  f = base;
  f.left.encoding = image_t::ENCODING_GRAY8;
  SetData(f.left, Bytes(100, 0));
  add("left GRAY8 64x48 holding 100 bytes", f, "expected width*height*1 = 3072");
  f = base;
  f.right.encoding = image_t::ENCODING_GRAY16;
  SetData(f.right, Bytes(2 * kW * kH - 1, 0));
  add("right GRAY16 64x48 holding an odd byte count", f, "expected width*height*2 = 6144");
  f = base;
  f.left.encoding = 9;
  add("left encoding 9", f, "");  // the bus may refuse it first
  f = base;
  SetData(f.left, EncodePng(cv::Mat(kH, kW, CV_8UC3, cv::Scalar(10, 20, 30))));
  add("left colour PNG", f, "expected 0, gray");
  f = base;
  SetData(f.left, Bytes(good_png.begin(), good_png.begin() + static_cast<long>(good_png.size() / 2)));
  add("left PNG truncated to half", f, "PNG does not decode: the data ends inside the image");
  f = base;
  SetData(f.left, Bytes(good_png.begin(), good_png.begin() + 20));
  add("left PNG truncated to 20 bytes", f, "PNG is truncated");
  f = base;
  SetData(f.left, good_png);
  f.left.data[0] = 'G';
  add("left PNG with a wrong signature", f, "PNG signature is wrong");
  f = base;
  SetData(f.left, PatchIhdr(good_png, 4096, 4096, false));
  add("left PNG header says 4096x4096 with the old CRC", f, "the header is corrupt");
  f = base;
  f.right = PngImage(48, 48, 4);
  f.right_model = PinholeModel(48, 48, 0.2);
  add("right 48x48 beside a 64x48 left, each as its model", f, "expected a pair of one size");
  f = base;
  f.left_model.type = "bogus";
  add("left model type 'bogus'", f, "camera model");
  f = base;
  f.left_model.params.clear();
  f.left_model.num_params = 0;
  add("left model with no parameters", f, "camera model");
  f = base;
  std::fill(f.right_model.params.begin() + 7, f.right_model.params.end(), 0.0);
  add("right model with a zero quaternion", f, "camera model");
  f = base;
  f.left.data.clear();
  f.left.size = 0;
  add("left PNG with no bytes", f, "PNG is truncated: 0 bytes");
  return out;
}

// Commands that would change what the rover does, as anyone on the LAN could send them:
// with no tag, and with a made-up tag under the executor's name. A deployment with keys
// refuses every one; one without keys obeys them (that is what keys are for).
template <class Msg>
void AddSpoofed(std::vector<Packet>& out, const std::string& channel, const std::string& what, Msg m,
                std::mt19937& rng, std::int64_t counter) {
  m.auth.sender = "fault_inject";
  m.auth.counter = counter;
  m.auth.tag_size = 0;
  m.auth.tag.clear();
  out.push_back({channel, channel + " spoofed " + what + ", unsigned", Encode(m), ""});
  m.auth.sender = "sequence_executor@rover:1";
  m.auth.tag.resize(32);
  for (auto& b : m.auth.tag) b = static_cast<std::uint8_t>(rng());
  m.auth.tag_size = 32;
  out.push_back({channel, channel + " spoofed " + what + ", a made-up tag in the executor's name", Encode(m), ""});
}

std::vector<Packet> Spoofed(const std::string& channel, const PacketOptions& o) {
  using namespace rover_msgs;
  std::vector<Packet> out;
  std::mt19937 rng(o.seed);
  // A counter far above any real one (they count wall-clock microseconds).
  const std::int64_t counter = std::int64_t{1} << 62;
  const std::int64_t now = o.now_utime;
  if (channel == "SEQUENCE_SUBMIT") {
    sequence_submit_t m{};
    m.utime = now;
    m.pub_seq = PubSeq(2);
    m.submission_id = kFakeId + 1;
    m.name = "spoofed.seq";
    m.text = "drive 10 cm\n";
    AddSpoofed(out, channel, "submit of 'drive 10 cm'", m, rng, counter);
  } else if (channel == "SEQUENCE_CONTROL") {
    sequence_control_t m{};
    m.utime = now;
    m.pub_seq = PubSeq(2);
    m.action = sequence_control_t::ACTION_ABORT;
    m.reason = "spoofed";
    AddSpoofed(out, channel, "abort", m, rng, counter);
  } else if (channel == "MOBILITY_COMMAND") {
    mobility_command_t m{};
    m.utime = now;
    m.pub_seq = PubSeq(2);
    m.command_id = kFakeId + 1;
    m.type = mobility_command_t::TYPE_STOP;
    AddSpoofed(out, channel, "STOP", m, rng, counter);
    m.command_id = kFakeId + 2;
    m.type = mobility_command_t::TYPE_TURN;
    m.turn_rad = 1.0;
    AddSpoofed(out, channel, "turn 1 rad", m, rng, counter + 1);
  } else if (channel == "KEEPOUT_ZONES") {
    keepout_zones_t m{};
    m.utime = now;
    m.pub_seq = PubSeq(2);
    keepout_zone_t zone{};
    zone.name = "spoofed";
    zone.shape = keepout_zone_t::SHAPE_CIRCLE;
    zone.radius_m = 50;  // around everything: every step would be refused
    m.zones = {zone};
    m.num_zones = 1;
    AddSpoofed(out, channel, "a 50 m zone around the rover", m, rng, counter);
  } else if (channel == "NEW_SITE") {
    new_site_t m{};
    m.utime = now;
    m.pub_seq = PubSeq(2);
    m.site_index = 7;
    AddSpoofed(out, channel, "new site 7", m, rng, counter);
  }
  return out;
}

}  // namespace

std::uint32_t InjectorPublisherId() {
  std::uint32_t h = 2166136261u;  // FNV-1a, as the Bus stamps a publisher's name
  for (unsigned char c : std::string("fault_inject")) {
    h ^= c;
    h *= 16777619u;
  }
  return h;
}

const std::vector<ChannelInfo>& AllChannels() {
  static const std::vector<ChannelInfo> channels = {
      {"HEARTBEAT", "heartbeat_t"},           {"ROVER_CLOCK", "rover_clock_t"},
      {"IMU", "imu_t"},                       {"WHEEL_ODOMETRY", "wheel_odometry_t"},
      {"POSE", "pose_t"},                     {"NEW_SITE", "new_site_t"},
      {"MOBILITY_COMMAND", "mobility_command_t"}, {"MOBILITY_STATUS", "mobility_status_t"},
      {"CAPTURE_REQUEST", "capture_request_t"}, {"STEREO_FRAME", "stereo_frame_t"},
      {"HAZCAM_FRAME", "stereo_frame_t"},
      {"VO_UPDATE", "vo_update_t"},           {"KEEPOUT_ZONES", "keepout_zones_t"},
      {"HAZARD_STATUS", "hazard_status_t"},   {"HAZARD_QUERY", "hazard_query_t"},
      {"HAZARD_REPLY", "hazard_reply_t"},     {"SEQUENCE_SUBMIT", "sequence_submit_t"},
      {"SEQUENCE_CONTROL", "sequence_control_t"}, {"SEQUENCE_STATUS", "sequence_status_t"},
      {"STEP_REPORT", "step_report_t"},       {"SIM_TRUTH", "sim_truth_t"},
      {"TRAVERSABILITY_MAP", "traversability_map_t"}};
  return channels;
}

const ChannelInfo& Channel(const std::string& channel) {
  for (const auto& c : AllChannels())
    if (c.channel == channel) return c;
  throw std::invalid_argument("unknown channel " + channel + " (expected one of common/bus/channels.hpp)");
}

const std::vector<std::string>& Groups() {
  static const std::vector<std::string> groups = {"malformed", "values", "times", "images", "spoofed"};
  return groups;
}

Bytes SampleMessage(const std::string& channel, const PacketOptions& options) {
  Channel(channel);
  return Sample(channel, options.now_utime);
}

std::vector<Packet> BuildPackets(const std::string& group, const std::string& channel,
                                 const PacketOptions& options) {
  const ChannelInfo& info = Channel(channel);
  if (group == "images") {
    return channel == "STEREO_FRAME" || channel == "HAZCAM_FRAME" ? Images(channel, options) : std::vector<Packet>{};
  }
  if (group == "spoofed") return Spoofed(channel, options);
  const Bytes base = Sample(channel, options.now_utime);
  const Layout layout = Walk(Schema::Embedded(), info.type, base.data(), base.size());
  if (group == "malformed") return Malformed(channel, base, layout, options);
  if (group == "values") return Values(channel, base, layout);
  if (group == "times") return Times(channel, base, layout, options);
  throw std::invalid_argument("unknown group " + group +
                              " (expected malformed, values, times, images or spoofed)");
}

}  // namespace rover::fault
