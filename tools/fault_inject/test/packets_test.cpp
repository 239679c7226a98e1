// fault_inject's packets: the schema walk finds the real fields of every message type
// (checked against the generated C++ decoders), and each packet carries exactly the fault
// its label names.
#include "fault_inject/lcm_schema.hpp"
#include "fault_inject/packets.hpp"

#include <gtest/gtest.h>

#include <rover_msgs/capture_request_t.hpp>
#include <rover_msgs/hazard_query_t.hpp>
#include <rover_msgs/hazard_reply_t.hpp>
#include <rover_msgs/hazard_status_t.hpp>
#include <rover_msgs/heartbeat_t.hpp>
#include <rover_msgs/imu_t.hpp>
#include <rover_msgs/keepout_zones_t.hpp>
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
#include <rover_msgs/traversability_map_t.hpp>
#include <rover_msgs/vo_update_t.hpp>
#include <rover_msgs/wheel_odometry_t.hpp>

#include <cmath>
#include <functional>
#include <map>
#include <set>

namespace rover::fault {
namespace {

PacketOptions Options() {
  PacketOptions o;
  o.now_utime = 123456789;
  o.bomb_side = 1024;  // small: the unit tests need not deflate hundreds of MB
  o.max_payload_bytes = [](const std::string& ch) -> std::size_t { return ch == "STEREO_FRAME" || ch == "HAZCAM_FRAME" ? 4 << 20 : 65536; };
  return o;
}

// Decodes `bytes` with the generated C++ of the channel's type and re-encodes it.
// Returns false when it does not decode. Only for well-formed packets (values, times).
template <class Msg>
bool RoundTrip(const Bytes& bytes, Bytes* again) {
  Msg m;
  if (m.decode(bytes.data(), 0, static_cast<int>(bytes.size())) != static_cast<int>(bytes.size())) return false;
  again->resize(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(again->data(), 0, static_cast<int>(again->size()));
  return true;
}

bool Decodes(const std::string& channel, const Bytes& bytes, Bytes* again) {
  using namespace rover_msgs;
  static const std::map<std::string, std::function<bool(const Bytes&, Bytes*)>> decoders = {
      {"HEARTBEAT", RoundTrip<heartbeat_t>},           {"ROVER_CLOCK", RoundTrip<rover_clock_t>},
      {"IMU", RoundTrip<imu_t>},                       {"WHEEL_ODOMETRY", RoundTrip<wheel_odometry_t>},
      {"POSE", RoundTrip<pose_t>},                     {"NEW_SITE", RoundTrip<new_site_t>},
      {"MOBILITY_COMMAND", RoundTrip<mobility_command_t>}, {"MOBILITY_STATUS", RoundTrip<mobility_status_t>},
      {"CAPTURE_REQUEST", RoundTrip<capture_request_t>}, {"STEREO_FRAME", RoundTrip<stereo_frame_t>},
      {"HAZCAM_FRAME", RoundTrip<stereo_frame_t>},
      {"VO_UPDATE", RoundTrip<vo_update_t>},           {"KEEPOUT_ZONES", RoundTrip<keepout_zones_t>},
      {"HAZARD_STATUS", RoundTrip<hazard_status_t>},   {"HAZARD_QUERY", RoundTrip<hazard_query_t>},
      {"HAZARD_REPLY", RoundTrip<hazard_reply_t>},     {"SEQUENCE_SUBMIT", RoundTrip<sequence_submit_t>},
      {"SEQUENCE_CONTROL", RoundTrip<sequence_control_t>}, {"SEQUENCE_STATUS", RoundTrip<sequence_status_t>},
      {"STEP_REPORT", RoundTrip<step_report_t>},       {"SIM_TRUTH", RoundTrip<sim_truth_t>},
      {"TRAVERSABILITY_MAP", RoundTrip<traversability_map_t>}};
  return decoders.at(channel)(bytes, again);
}

Layout WalkSample(const std::string& channel) {
  const Bytes b = SampleMessage(channel, Options());
  return Walk(Schema::Embedded(), Channel(channel).type, b.data(), b.size());
}

const FieldLocation* Find(const Layout& l, FieldKind kind, const std::string& path) {
  for (const auto& f : l.fields)
    if (f.kind == kind && f.path == path) return &f;
  return nullptr;
}

TEST(FaultSchema, EveryChannelTypeIsInTheEmbeddedLcmFiles) {
  const Schema& s = Schema::Embedded();
  for (const auto& c : AllChannels()) EXPECT_TRUE(s.Has(c.type)) << c.type;
  EXPECT_TRUE(s.Has("image_t"));
  EXPECT_TRUE(s.Has("auth_t"));
  EXPECT_EQ(AllChannels().size(), 22u);  // every channel of common/bus/channels.hpp
  EXPECT_EQ(Channel("HAZCAM_FRAME").type, "stereo_frame_t");
}

TEST(FaultSchema, WalkConsumesEverySampleExactly) {
  for (const auto& c : AllChannels()) {
    const Bytes b = SampleMessage(c.channel, Options());
    EXPECT_EQ(Walk(Schema::Embedded(), c.type, b.data(), b.size()).end, b.size()) << c.channel;
    // One byte short: the walk notices.
    EXPECT_THROW(Walk(Schema::Embedded(), c.type, b.data(), b.size() - 1), std::runtime_error) << c.channel;
  }
}

TEST(FaultSchema, FindsTheHeartbeatProcessNameAfterItsUtime) {
  const Bytes b = SampleMessage("HEARTBEAT", Options());
  const Layout l = WalkSample("HEARTBEAT");
  const FieldLocation* name = Find(l, FieldKind::kStringLength, "process");
  ASSERT_NE(name, nullptr);
  EXPECT_EQ(name->offset, 16u);  // fingerprint 8 + utime 8
  EXPECT_EQ(GetInt(&b[name->offset], 4), 13);  // "fault_inject" and its NUL
  EXPECT_NE(Find(l, FieldKind::kEnum, "state"), nullptr);
  EXPECT_NE(Find(l, FieldKind::kTime, "utime"), nullptr);
}

TEST(FaultSchema, FindsNestedCountsStringsAndTimesOfAStereoFrame) {
  const Layout l = WalkSample("STEREO_FRAME");
  for (const char* path : {"left.size", "right.size", "left_model.num_params", "right_model.num_params"})
    EXPECT_NE(Find(l, FieldKind::kCount, path), nullptr) << path;
  for (const char* path : {"purpose", "left_model.type", "right_model.type"})
    EXPECT_NE(Find(l, FieldKind::kStringLength, path), nullptr) << path;
  EXPECT_NE(Find(l, FieldKind::kEnum, "left.encoding"), nullptr);
  EXPECT_NE(Find(l, FieldKind::kEnum, "pose_at_capture.source"), nullptr);
  const FieldLocation* top = Find(l, FieldKind::kTime, "utime");
  const FieldLocation* nested = Find(l, FieldKind::kTime, "pose_at_capture.utime");
  ASSERT_TRUE(top && nested);
  EXPECT_TRUE(top->top_level);
  EXPECT_FALSE(nested->top_level);
}

TEST(FaultSchema, FindsArraysOfStructsAndSharedCounts) {
  const Layout zones = WalkSample("KEEPOUT_ZONES");
  EXPECT_NE(Find(zones, FieldKind::kCount, "num_zones"), nullptr);
  EXPECT_NE(Find(zones, FieldKind::kCount, "zones[1].num_vertices"), nullptr);
  EXPECT_NE(Find(zones, FieldKind::kStringLength, "zones[0].name"), nullptr);
  EXPECT_NE(Find(zones, FieldKind::kCount, "auth.tag_size"), nullptr);
  const Layout query = WalkSample("HAZARD_QUERY");
  EXPECT_NE(Find(query, FieldKind::kCount, "num_poses"), nullptr);
  int xs = 0;
  for (const auto& f : query.fields) xs += f.kind == FieldKind::kDouble && f.path == "x";
  EXPECT_EQ(xs, 2);
}

TEST(FaultSchema, ParseErrorsNameTheFile) {
  EXPECT_THROW(Schema::Parse({{"bad.lcm", "struct x { int32_t a }"}}), std::runtime_error);
  try {
    Schema::Parse({{"bad.lcm", "struct x { int32_t a }"}});
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("bad.lcm"), std::string::npos);
  }
}

TEST(FaultPackets, EveryGroupBuildsForEveryChannelWithUniqueLabels) {
  std::set<std::string> labels;
  std::map<std::string, int> per_group;
  for (const auto& group : Groups()) {
    for (const auto& c : AllChannels()) {
      for (const auto& p : BuildPackets(group, c.channel, Options())) {
        EXPECT_EQ(p.channel, c.channel);
        EXPECT_TRUE(labels.insert(p.label).second) << "duplicate label " << p.label;
        EXPECT_FALSE(p.bytes.empty() && p.label.find("no bytes") == std::string::npos) << p.label;
        ++per_group[group];
      }
    }
  }
  // malformed: >= 11 per channel (truncations, fingerprints, random, oversize) and five
  // per length field; every channel has a utime but HEARTBEAT's is there too.
  EXPECT_GE(per_group["malformed"], 20 * 11);
  EXPECT_GE(per_group["times"], 20 * 4);
  EXPECT_GE(per_group["values"], 60);
  EXPECT_GE(per_group["images"], 20);
  EXPECT_EQ(per_group["spoofed"], 12);  // two per command, a STOP and a turn on MOBILITY_COMMAND
  EXPECT_THROW(BuildPackets("nonsense", "IMU", Options()), std::invalid_argument);
  EXPECT_THROW(BuildPackets("values", "NOT_A_CHANNEL", Options()), std::invalid_argument);
}

TEST(FaultPackets, LengthFieldsAreEditedInPlace) {
  const Bytes base = SampleMessage("HEARTBEAT", Options());
  int found = 0;
  for (const auto& p : BuildPackets("malformed", "HEARTBEAT", Options())) {
    if (p.label == "HEARTBEAT malformed process: string length 0") {
      ++found;
      ASSERT_EQ(p.bytes.size(), base.size());
      EXPECT_EQ(GetInt(&p.bytes[16], 4), 0);
      EXPECT_TRUE(std::equal(base.begin() + 20, base.end(), p.bytes.begin() + 20));
    }
    if (p.label == "HEARTBEAT malformed detail: string length -1") {
      ++found;
      EXPECT_NE(p.bytes, base);
    }
  }
  EXPECT_EQ(found, 2);
}

TEST(FaultPackets, ValueAndTimePacketsAreWellFormedAndCarryTheirFault) {
  for (const auto& c : AllChannels()) {
    const Bytes base = SampleMessage(c.channel, Options());
    for (const char* group : {"values", "times"}) {
      for (const auto& p : BuildPackets(group, c.channel, Options())) {
        Bytes again;
        ASSERT_TRUE(Decodes(c.channel, p.bytes, &again)) << p.label;
        EXPECT_EQ(again, p.bytes) << p.label;  // a valid encoding, byte for byte
        EXPECT_NE(p.bytes, base) << p.label;
      }
    }
  }
  // Spot checks through the generated types.
  for (const auto& p : BuildPackets("values", "IMU", Options())) {
    if (p.label != "IMU values accel[2] = NaN") continue;
    rover_msgs::imu_t m{};
    ASSERT_GT(m.decode(p.bytes.data(), 0, static_cast<int>(p.bytes.size())), 0);
    EXPECT_TRUE(std::isnan(m.accel[2])) << m.accel[2];
    EXPECT_EQ(m.accel[1], 0.0);
  }
  int times = 0;
  for (const auto& p : BuildPackets("times", "POSE", Options())) {
    rover_msgs::pose_t m{};
    ASSERT_GT(m.decode(p.bytes.data(), 0, static_cast<int>(p.bytes.size())), 0);
    if (p.label == "POSE times utime = now + 1e12 us") {
      EXPECT_EQ(m.utime, 123456789 + 1000000000000);
      ++times;
    }
  }
  EXPECT_EQ(times, 1);
}

TEST(FaultPackets, OversizedPacketsPassTheBoundAndStillDecodeWhenGrownThroughAString) {
  const auto o = Options();
  for (const auto& c : AllChannels()) {
    int oversized = 0;
    for (const auto& p : BuildPackets("malformed", c.channel, o)) {
      if (p.label.find("oversized") == std::string::npos) continue;
      ++oversized;
      EXPECT_GT(p.bytes.size(), o.max_payload_bytes(c.channel)) << p.label;
      Bytes again;
      if (p.label.find("string") != std::string::npos) {
        EXPECT_TRUE(Decodes(c.channel, p.bytes, &again)) << p.label;
      }
    }
    EXPECT_EQ(oversized, 1) << c.channel;
  }
}

TEST(FaultPackets, ImagePacketsAreWellFormedFramesWithDistinctIds) {
  for (const char* channel : {"STEREO_FRAME", "HAZCAM_FRAME"}) {
    std::set<std::int64_t> ids;
    const auto packets = BuildPackets("images", channel, Options());
    EXPECT_GE(packets.size(), 20u) << channel;
    for (const auto& p : packets) {
      EXPECT_EQ(p.channel, channel) << p.label;
      EXPECT_EQ(p.label.rfind(std::string(channel) + " images ", 0), 0u) << p.label;
      rover_msgs::stereo_frame_t f;
      ASSERT_EQ(f.decode(p.bytes.data(), 0, static_cast<int>(p.bytes.size())), static_cast<int>(p.bytes.size()))
          << p.label;
      EXPECT_TRUE(ids.insert(f.frame_id).second) << p.label;
      if (p.label.find("65535x65535") != std::string::npos) {
        // The PNG's own header claims the size; the bytes are a small real PNG.
        ASSERT_GT(f.left.data.size(), 24u);
        EXPECT_EQ(GetInt(&f.left.data[16], 4), 65535);
        EXPECT_LT(f.left.data.size(), 20000u);
      }
    }
  }
  // The HAZCAM pair's readers get the very same bad images as the NAVCAM pair's.
  const auto navcam = BuildPackets("images", "STEREO_FRAME", Options());
  const auto hazcam = BuildPackets("images", "HAZCAM_FRAME", Options());
  ASSERT_EQ(navcam.size(), hazcam.size());
  for (std::size_t i = 0; i < navcam.size(); ++i) {
    EXPECT_EQ(navcam[i].bytes, hazcam[i].bytes) << hazcam[i].label;
    EXPECT_EQ(navcam[i].expect_reason, hazcam[i].expect_reason) << hazcam[i].label;
  }
  EXPECT_TRUE(BuildPackets("images", "IMU", Options()).empty());
}

TEST(FaultPackets, SpoofedCommandsAreWellFormedUnsignedOrWithAMadeUpTag) {
  int tagged = 0, unsigned_ = 0;
  for (const char* channel : {"SEQUENCE_SUBMIT", "SEQUENCE_CONTROL", "MOBILITY_COMMAND", "KEEPOUT_ZONES", "NEW_SITE"}) {
    const auto packets = BuildPackets("spoofed", channel, Options());
    ASSERT_FALSE(packets.empty()) << channel;
    for (const auto& p : packets) {
      Bytes again;
      ASSERT_TRUE(Decodes(channel, p.bytes, &again)) << p.label;
      EXPECT_EQ(again, p.bytes) << p.label;
      if (p.label.find("unsigned") != std::string::npos) ++unsigned_;
      if (p.label.find("made-up tag") != std::string::npos) ++tagged;
    }
  }
  EXPECT_EQ(tagged, 6);
  EXPECT_EQ(unsigned_, 6);
  rover_msgs::sequence_control_t abort;
  const auto control = BuildPackets("spoofed", "SEQUENCE_CONTROL", Options());
  ASSERT_EQ(abort.decode(control[1].bytes.data(), 0, static_cast<int>(control[1].bytes.size())),
            static_cast<int>(control[1].bytes.size()));
  EXPECT_EQ(abort.action, int{rover_msgs::sequence_control_t::ACTION_ABORT});
  EXPECT_EQ(abort.auth.tag_size, 32);
  EXPECT_TRUE(BuildPackets("spoofed", "IMU", Options()).empty());
}

TEST(FaultPackets, SamePacketsForTheSameSeed) {
  const auto a = BuildPackets("malformed", "POSE", Options());
  const auto b = BuildPackets("malformed", "POSE", Options());
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) EXPECT_EQ(a[i].bytes, b[i].bytes) << a[i].label;
}

}  // namespace
}  // namespace rover::fault
