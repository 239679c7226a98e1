#include "bus/signing.hpp"

#include <gtest/gtest.h>
#include "bus/channels.hpp"

#include <rover_msgs/heartbeat_t.hpp>
#include <rover_msgs/imu_t.hpp>
#include <rover_msgs/rover_clock_t.hpp>
#include <rover_msgs/keepout_zones_t.hpp>
#include <rover_msgs/mobility_command_t.hpp>
#include <rover_msgs/new_site_t.hpp>
#include <rover_msgs/sequence_control_t.hpp>
#include <rover_msgs/sequence_submit_t.hpp>

#include <sys/stat.h>

#include <filesystem>
#include <fstream>

namespace fs = std::filesystem;
using rover::auth::Key;
using rover::auth::Signer;
using rover::auth::Verifier;
using rover::bus::SignMessage;
using rover::bus::VerifyMessage;
using rover_msgs::sequence_control_t;

namespace {

Key TestKey(std::uint8_t seed = 3) {
  std::vector<std::uint8_t> bytes(32);
  for (std::size_t i = 0; i < bytes.size(); ++i) bytes[i] = static_cast<std::uint8_t>(seed * 11 + 5 * i);
  return Key::FromBytes(bytes, "test key");
}

sequence_control_t Abort(const std::string& reason) {
  sequence_control_t msg{};
  msg.utime = 123456;
  msg.pub_seq = 7;
  msg.action = sequence_control_t::ACTION_ABORT;
  msg.reason = reason;
  return msg;
}

// The message as it arrives: encoded and decoded, as LCM carries it.
template <class Msg>
Msg OverTheWire(const Msg& msg) {
  const auto bytes = rover::bus::EncodeMessage(msg);
  Msg out;
  EXPECT_EQ(out.decode(bytes.data(), 0, static_cast<int>(bytes.size())), static_cast<int>(bytes.size()));
  return out;
}

}  // namespace

static_assert(rover::bus::Authenticated<rover_msgs::sequence_submit_t>);
static_assert(rover::bus::Authenticated<rover_msgs::sequence_control_t>);
static_assert(rover::bus::Authenticated<rover_msgs::mobility_command_t>);
static_assert(rover::bus::Authenticated<rover_msgs::keepout_zones_t>);
static_assert(rover::bus::Authenticated<rover_msgs::new_site_t>);
static_assert(rover::bus::Authenticated<rover_msgs::heartbeat_t>);  // evidence of life: a replay must not pass
static_assert(rover::bus::Authenticated<rover_msgs::rover_clock_t>);  // time: only the time source
static_assert(!rover::bus::Authenticated<rover_msgs::imu_t>);

TEST(Signing, SignedMessageVerifiesAfterTheWireOnce) {
  Signer signer(TestKey(), "rover_seq");
  Verifier verifier(TestKey());
  sequence_control_t msg = Abort("operator");
  SignMessage(msg, signer);
  EXPECT_EQ(msg.auth.sender, "rover_seq");
  EXPECT_GT(msg.auth.counter, 0);
  EXPECT_EQ(msg.auth.tag_size, 32);
  ASSERT_EQ(msg.auth.tag.size(), 32u);

  const sequence_control_t received = OverTheWire(msg);
  EXPECT_EQ(VerifyMessage(received, verifier), std::nullopt);
  // The same bytes again: a replay.
  const auto replay = VerifyMessage(OverTheWire(msg), verifier);
  ASSERT_TRUE(replay);
  EXPECT_NE(replay->find("replayed or old counter"), std::string::npos) << *replay;
}

TEST(Signing, UnsignedForgedAndAlteredMessagesAreRejected) {
  Signer signer(TestKey(), "rover_seq");
  Signer forger(TestKey(4), "rover_seq");
  Verifier verifier(TestKey());

  const auto unsigned_reason = VerifyMessage(OverTheWire(Abort("spoof")), verifier);
  ASSERT_TRUE(unsigned_reason);
  EXPECT_NE(unsigned_reason->find("missing tag"), std::string::npos) << *unsigned_reason;

  sequence_control_t forged = Abort("spoof");
  SignMessage(forged, forger);
  const auto forged_reason = VerifyMessage(OverTheWire(forged), verifier);
  ASSERT_TRUE(forged_reason);
  EXPECT_NE(forged_reason->find("wrong tag"), std::string::npos) << *forged_reason;

  // Every signed field is covered: change any one and the tag no longer fits.
  sequence_control_t good = Abort("pause please");
  good.action = sequence_control_t::ACTION_PAUSE;
  SignMessage(good, signer);
  auto altered = [&](auto change) {
    sequence_control_t m = good;
    change(m);
    return VerifyMessage(OverTheWire(m), verifier).has_value();
  };
  EXPECT_TRUE(altered([](sequence_control_t& m) { m.action = sequence_control_t::ACTION_ABORT; }));
  EXPECT_TRUE(altered([](sequence_control_t& m) { m.reason = "pause pleasE"; }));
  EXPECT_TRUE(altered([](sequence_control_t& m) { m.utime += 1; }));
  EXPECT_TRUE(altered([](sequence_control_t& m) { m.pub_seq += 1; }));
  EXPECT_TRUE(altered([](sequence_control_t& m) { m.auth.counter += 1; }));
  EXPECT_TRUE(altered([](sequence_control_t& m) { m.auth.sender = "sequence_executor"; }));
  EXPECT_TRUE(altered([](sequence_control_t& m) { m.auth.tag[0] ^= 0x80; }));
  // None of those moved the counter: the genuine message is still accepted, once.
  EXPECT_EQ(VerifyMessage(OverTheWire(good), verifier), std::nullopt);
}

TEST(Signing, TagSizeThatDisagreesWithTheTagIsRejected) {
  Signer signer(TestKey(), "rover_seq");
  Verifier verifier(TestKey());
  sequence_control_t msg = Abort("x");
  SignMessage(msg, signer);
  msg.auth.tag_size = 31;  // as a hand-built (never decoded) message could have
  const auto reason = VerifyMessage(msg, verifier);
  ASSERT_TRUE(reason);
  EXPECT_NE(reason->find("disagrees"), std::string::npos) << *reason;
}

TEST(Signing, TagOfOneTypeDoesNotFitAnother) {
  // A submit and a control message signed by the same sender: their encodings start with
  // different type fingerprints, so a tag cannot be moved from one type to the other.
  Signer signer(TestKey(), "rover_seq");
  Verifier verifier(TestKey());
  rover_msgs::sequence_submit_t submit{};
  submit.submission_id = 1;
  submit.name = "a.seq";
  submit.text = "drive 1 m\n";
  SignMessage(submit, signer);
  sequence_control_t control = Abort("x");
  control.auth = submit.auth;
  EXPECT_TRUE(VerifyMessage(OverTheWire(control), verifier));
  EXPECT_EQ(VerifyMessage(OverTheWire(submit), verifier), std::nullopt);
}

TEST(Signing, ConfiguredKeyFromTheAuthSection) {
  using rover::config::ConfigError;
  using rover::config::ConfigNode;
  const fs::path dir = fs::path(ROVER_BINARY_DIR) / "test-out" / "signing_test";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string key_path = (dir / "rover.key").string();
  rover::auth::GenerateKeyFile(key_path);
  ::unsetenv("ROVER_KEY_FILE");  // the developer's own must not decide this test

  EXPECT_FALSE(rover::bus::LoadAuthSettings(ConfigNode::FromString("{}", "c.yaml")).key);
  EXPECT_FALSE(
      rover::bus::LoadAuthSettings(ConfigNode::FromString("auth: {required: false}", "c.yaml")).key);
  const auto settings = rover::bus::LoadAuthSettings(
      ConfigNode::FromString("auth: {key_file: " + key_path + ", required: true}", "c.yaml"));
  ASSERT_TRUE(settings.key);
  EXPECT_EQ(settings.key->size(), 32u);
  EXPECT_TRUE(settings.required);

  auto error_of = [](const std::string& yaml, std::optional<std::string> flag = std::nullopt) {
    try {
      rover::bus::LoadAuthSettings(ConfigNode::FromString(yaml, "c.yaml"), flag);
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  EXPECT_EQ(error_of("auth: {required: true}"),
            "c.yaml: auth.key_file: missing, and no --key or $ROVER_KEY_FILE (auth.required is "
            "true: expected the deployment's key file; ./rover seq keygen FILE makes one)");
  EXPECT_NE(error_of("auth: {key_file: " + key_path + ", requird: true}").find("requird"), std::string::npos);
  EXPECT_NE(error_of("auth: [1, 2]").find("expected a mapping"), std::string::npos);

  // --key, then the config, then $ROVER_KEY_FILE; a named key that does not load is an error.
  const std::string other_path = (dir / "other.key").string();
  rover::auth::GenerateKeyFile(other_path);
  auto tag_with = [](const rover::bus::AuthSettings& s) {
    const std::string m = "m";
    return rover::auth::ComputeTag(*s.key, reinterpret_cast<const std::uint8_t*>(m.data()), 1);
  };
  const auto from_config = rover::bus::LoadAuthSettings(
      ConfigNode::FromString("auth: {key_file: " + key_path + "}", "c.yaml"));
  const auto from_flag = rover::bus::LoadAuthSettings(
      ConfigNode::FromString("auth: {key_file: " + key_path + "}", "c.yaml"), other_path);
  ::setenv("ROVER_KEY_FILE", other_path.c_str(), 1);
  const auto from_env = rover::bus::LoadAuthSettings(ConfigNode::FromString("{}", "c.yaml"));
  const auto config_over_env = rover::bus::LoadAuthSettings(
      ConfigNode::FromString("auth: {key_file: " + key_path + "}", "c.yaml"));
  ::unsetenv("ROVER_KEY_FILE");
  ASSERT_TRUE(from_config.key && from_flag.key && from_env.key && config_over_env.key);
  EXPECT_EQ(tag_with(from_flag), tag_with(from_env));
  EXPECT_NE(tag_with(from_flag), tag_with(from_config));
  EXPECT_EQ(tag_with(config_over_env), tag_with(from_config));

  ::chmod(key_path.c_str(), 0644);
  EXPECT_EQ(error_of("auth: {key_file: " + key_path + "}"),
            "c.yaml: auth.key_file: " + key_path + ": mode 0644 gives other users access to the key "
            "(expected none: chmod o-rwx " + key_path + ")");
  EXPECT_NE(error_of("{}", key_path).find("argument --key: " + key_path + ": mode 0644"), std::string::npos);
  ::setenv("ROVER_KEY_FILE", (dir / "absent.key").c_str(), 1);
  EXPECT_NE(error_of("{}").find("$ROVER_KEY_FILE: " + (dir / "absent.key").string() + ": cannot open"),
            std::string::npos);
  ::unsetenv("ROVER_KEY_FILE");
}

// The Bus with MakeBusAuth, on LCM's in-process provider: what it publishes is signed
// after pub_seq is stamped, and what it receives is checked before any callback.
TEST(Signing, BusSignsWhatItPublishesAndRefusesForgeriesAndReplays) {
  rover::bus::Bus bus("memq://");
  bus.set_publisher("rover_seq");
  bus.set_auth(rover::bus::MakeBusAuth(TestKey(), "rover_seq"));
  std::vector<sequence_control_t> received;
  std::vector<std::vector<std::uint8_t>> raw;  // every packet, as a listener on the LAN sees it
  bus.Subscribe<sequence_control_t>(rover::channels::kSequenceControl,
                                    [&](const sequence_control_t& m) { received.push_back(m); });
  bus.Publish(rover::channels::kSequenceControl, Abort("operator"));
  while (bus.Handle(0)) {
  }
  ASSERT_EQ(received.size(), 1u);
  EXPECT_EQ(received[0].reason, "operator");
  EXPECT_EQ(received[0].auth.sender, rover::auth::InstanceName("rover_seq"));
  EXPECT_EQ(received[0].auth.tag_size, 32);
  EXPECT_EQ(bus.dropped(), 0);

  auto inject = [&](const sequence_control_t& m) {
    const auto bytes = rover::bus::EncodeMessage(m);
    bus.lcm().publish(rover::channels::kSequenceControl, bytes.data(), static_cast<unsigned>(bytes.size()));
    while (bus.Handle(0)) {
    }
  };
  inject(received[0]);  // the same bytes again
  EXPECT_EQ(received.size(), 1u);
  EXPECT_EQ(bus.dropped(), 1);
  EXPECT_NE(bus.last_drop().find("replayed or old counter"), std::string::npos) << bus.last_drop();

  inject(Abort("unsigned"));
  EXPECT_EQ(received.size(), 1u);
  EXPECT_EQ(bus.dropped(), 2);

  Signer forger(TestKey(8), "rover_seq");
  sequence_control_t forged = Abort("forged");
  SignMessage(forged, forger);
  inject(forged);
  EXPECT_EQ(received.size(), 1u);
  EXPECT_EQ(bus.dropped(), 3);
  EXPECT_NE(bus.last_drop().find("wrong tag"), std::string::npos) << bus.last_drop();

  // Signed elsewhere with the deployment's key (another tool): accepted.
  Signer other(TestKey(), "scenario_runner");
  sequence_control_t genuine = Abort("from the runner");
  SignMessage(genuine, other);
  inject(genuine);
  ASSERT_EQ(received.size(), 2u);
  EXPECT_EQ(received[1].reason, "from the runner");
}

// Two subscriptions on one Bus to a signed channel both get a signed message (LCM hands
// them the same datagram: the second must not call it a replay), and a replayed copy is
// refused by both.
TEST(Signing, TwoSubscriptionsToASignedChannelBothGetItAndBothRefuseAReplay) {
  rover::bus::Bus bus("memq://");
  bus.set_publisher("rover_seq");
  bus.set_auth(rover::bus::MakeBusAuth(TestKey(), "rover_seq"));
  std::vector<sequence_control_t> first, second;
  bus.Subscribe<sequence_control_t>(rover::channels::kSequenceControl,
                                    [&](const sequence_control_t& m) { first.push_back(m); });
  bus.Subscribe<sequence_control_t>(rover::channels::kSequenceControl,
                                    [&](const sequence_control_t& m) { second.push_back(m); });
  bus.Publish(rover::channels::kSequenceControl, Abort("operator"));
  while (bus.Handle(0)) {
  }
  ASSERT_EQ(first.size(), 1u);
  ASSERT_EQ(second.size(), 1u);
  EXPECT_EQ(bus.dropped(), 0) << bus.last_drop();
  const auto bytes = rover::bus::EncodeMessage(first[0]);
  for (int copy = 0; copy < 2; ++copy) {
    bus.lcm().publish(rover::channels::kSequenceControl, bytes.data(), static_cast<unsigned>(bytes.size()));
    while (bus.Handle(0)) {
    }
  }
  EXPECT_EQ(first.size(), 1u);
  EXPECT_EQ(second.size(), 1u);
  EXPECT_EQ(bus.dropped(), 4) << "two copies, each refused by both subscriptions";
}

// What the Bus counts of its refusals, per channel and for authentication, and a
// subscription for diagnostics that sees what the checked one refuses (rover_web reads the
// executor's heartbeat so when its own key is wrong).
TEST(Signing, RefusalsAreCountedPerChannelAndAnUnverifiedSubscriptionSeesWhatIsRefused) {
  rover::bus::Bus bus("memq://");
  bus.set_publisher("rover_web");
  bus.set_auth(rover::bus::MakeBusAuth(TestKey(), "rover_web"));
  std::vector<sequence_control_t> checked, unverified;
  bus.Subscribe<sequence_control_t>(rover::channels::kSequenceControl,
                                    [&](const sequence_control_t& m) { checked.push_back(m); });
  bus.SubscribeUnverified<sequence_control_t>(rover::channels::kSequenceControl,
                                              [&](const sequence_control_t& m) { unverified.push_back(m); });
  auto inject = [&](const sequence_control_t& m) {
    const auto bytes = rover::bus::EncodeMessage(m);
    bus.lcm().publish(rover::channels::kSequenceControl, bytes.data(), static_cast<unsigned>(bytes.size()));
    while (bus.Handle(0)) {
    }
  };
  inject(Abort("unsigned"));
  Signer forger(TestKey(8), "rover_seq");
  sequence_control_t forged = Abort("forged");
  SignMessage(forged, forger);
  inject(forged);
  EXPECT_TRUE(checked.empty());
  ASSERT_EQ(unverified.size(), 2u);
  EXPECT_EQ(unverified[1].reason, "forged");
  EXPECT_EQ(bus.auth_rejected(), 2);
  EXPECT_EQ(bus.dropped_on(rover::channels::kSequenceControl), 2);
  EXPECT_EQ(bus.dropped_on(rover::channels::kSequenceSubmit), 0);
  EXPECT_EQ(bus.last_drop_on(rover::channels::kSequenceControl).rfind("rejected: wrong tag from \"rover_seq\"", 0), 0u)
      << bus.last_drop_on(rover::channels::kSequenceControl);
  EXPECT_EQ(bus.last_auth_rejection().rfind(std::string(rover::channels::kSequenceControl) + ": wrong tag from", 0), 0u)
      << bus.last_auth_rejection();
  // A signed one: both take it, once each; nothing more is counted.
  bus.Publish(rover::channels::kSequenceControl, Abort("operator"));
  while (bus.Handle(0)) {
  }
  EXPECT_EQ(checked.size(), 1u);
  EXPECT_EQ(unverified.size(), 3u);
  EXPECT_EQ(bus.auth_rejected(), 2);
  EXPECT_EQ(bus.dropped(), 2);
}
