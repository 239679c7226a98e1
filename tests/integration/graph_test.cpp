// ./rover graph against a real run: the demo scenario (configs/deploy/sim_vo.yaml, a
// sequence with a drive, zones and a goto with avoidance) runs on a private bus and is
// recorded; every (publisher, channel) in its log must be declared by the graph, and every
// publication the graph declares unconditionally for a process that ran must be in the log.
#include "integration/run_support.hpp"
#include "logcheck/log_check.hpp"

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

namespace rover::test {
namespace {

struct Declared {
  std::map<std::string, std::map<std::string, std::string>> publishes;  // process -> channel -> when
  std::map<std::string, std::set<std::string>> subscribes;
};

Declared ParseList(const std::string& text) {
  Declared d;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream words(line);
    std::string process, verb, channel, when;
    words >> process >> verb >> channel;
    std::getline(words >> std::ws, when);
    if (verb == "publishes") {
      d.publishes[process][channel] = when;
    } else if (verb == "subscribes") {
      d.subscribes[process].insert(channel);
    } else {
      ADD_FAILURE() << "rover_graph --list: unexpected line: " << line;
    }
  }
  return d;
}

// (publisher name, channel) of every message in the log; a publisher id no name maps to
// stays "0x..." (logcheck's form), which no declaration can match.
std::set<std::pair<std::string, std::string>> SeenOnTheBus(const std::string& path,
                                                           const std::vector<std::string>& names) {
  std::map<std::uint32_t, std::string> by_id;
  for (const auto& n : names) by_id[logcheck::PublisherId(n)] = n;
  std::set<std::pair<std::string, std::string>> seen;
  lcm::LogFile log(path, "r");
  EXPECT_TRUE(log.good()) << path;
  for (const lcm::LogEvent* ev = log.readNextEvent(); ev != nullptr; ev = log.readNextEvent()) {
    const auto* type = logcheck::FindChannel(ev->channel);
    if (type == nullptr) {
      seen.insert({"(unknown channel)", ev->channel});
      continue;
    }
    const auto read = logcheck::ReadStamp(*type, static_cast<const std::uint8_t*>(ev->data),
                                          static_cast<std::size_t>(ev->datalen));
    if (!read.stamp) {
      seen.insert({"(unreadable: " + read.error + ")", ev->channel});
      continue;
    }
    const auto it = by_id.find(read.stamp->publisher_id);
    seen.insert({it != by_id.end() ? it->second : read.stamp->publisher, ev->channel});
  }
  return seen;
}

TEST(Graph, EveryPublicationOnTheBusIsDeclaredAndEveryDeclaredOneIsSeen) {
  const std::string deployment = "configs/deploy/sim_vo.yaml";  // the demo scenario's set
  const auto listed = RunCommand(Bin("rover_graph") + " " + deployment + " --list");
  ASSERT_EQ(listed.exit_code, 0) << listed.output;
  const Declared declared = ParseList(listed.output);
  ASSERT_EQ(declared.publishes.size(), 6u) << listed.output;
  EXPECT_TRUE(declared.subscribes.at("sequence_executor").count("SEQUENCE_SUBMIT")) << listed.output;
  EXPECT_TRUE(declared.subscribes.at("visual_odometry").count("STEREO_FRAME")) << listed.output;

  const std::string out = OutDir("graph_demo");
  const auto run = RunCommand(Bin("scenario_runner") + " configs/scenarios/demo.yaml --out " + out +
                              " --quiet --no-plot");
  ASSERT_EQ(run.exit_code, 0) << run.output;

  // What the test harness publishes itself: the runner submits the sequence, the recorder
  // records. They may publish only what the set takes from outside (nobody in it publishes).
  std::set<std::string> from_outside{"HEARTBEAT"};
  for (const auto& [process, channels] : declared.subscribes) {
    for (const auto& c : channels) {
      bool published = false;
      for (const auto& [p, pubs] : declared.publishes) published = published || pubs.count(c);
      if (!published) from_outside.insert(c);
    }
  }
  std::vector<std::string> names{"scenario_runner", "rover_recorder"};
  for (const auto& [p, pubs] : declared.publishes) names.push_back(p);
  const auto seen = SeenOnTheBus(out + "/log.lcm", names);
  ASSERT_GT(seen.size(), 10u);
  for (const auto& [publisher, channel] : seen) {
    if (publisher == "scenario_runner" || publisher == "rover_recorder") {
      EXPECT_TRUE(from_outside.count(channel)) << publisher << " published " << channel
                                               << ", which a process of the set publishes";
      continue;
    }
    ASSERT_TRUE(declared.publishes.count(publisher))
        << "a message on " << channel << " from " << publisher << ", not a process of " << deployment;
    EXPECT_TRUE(declared.publishes.at(publisher).count(channel))
        << publisher << " published " << channel << " but does not declare it (its main's DeclarePublications)";
  }
  for (const auto& [process, pubs] : declared.publishes) {
    for (const auto& [channel, when] : pubs) {
      if (!when.empty()) continue;  // conditional: "when ..."
      EXPECT_TRUE(seen.count({process, channel}))
          << process << " declares " << channel << " unconditionally, but published none in the demo";
    }
  }
}

TEST(Graph, DrawsEveryProcessAndChannelAndRefusesBadArguments) {
  const std::string out = OutDir("graph_draw");
  const auto dot = RunCommand(Bin("rover_graph") + " configs/deploy/sim_vo.yaml --out " + out + "/set.dot");
  ASSERT_EQ(dot.exit_code, 0) << dot.output;
  std::ifstream in(out + "/set.dot");
  std::stringstream text;
  text << in.rdbuf();
  for (const char* s : {"\"rover_sim\"", "\"sequence_executor\"", "\"ch:POSE\"", "\"state_estimator\" -> \"ch:POSE\"",
                        "\"ch:POSE\" -> \"sequence_executor\"", "HEARTBEAT\\n(from every process)",
                        "outside -> \"ch:SEQUENCE_SUBMIT\""}) {
    EXPECT_NE(text.str().find(s), std::string::npos) << s << " not in\n" << text.str();
  }
  // A conditional publication is dashed.
  EXPECT_NE(text.str().find("\"camera_capture\" -> \"ch:HAZCAM_FRAME\" [style=dashed"), std::string::npos);

  const auto bad_ext = RunCommand(Bin("rover_graph") + " configs/deploy/sim_vo.yaml --out x.jpg");
  EXPECT_EQ(bad_ext.exit_code, 2) << bad_ext.output;
  EXPECT_NE(bad_ext.output.find("expected a name ending .svg, .png or .dot"), std::string::npos) << bad_ext.output;
  const auto missing = RunCommand(Bin("rover_graph") + " configs/deploy/no_such.yaml");
  EXPECT_EQ(missing.exit_code, 2) << missing.output;
  // A program that declares nothing refuses --channels in one line instead of running.
  const auto undeclared = RunCommand(Bin("sample_mobility_driver") + " --channels --lcm-url memq://");
  EXPECT_EQ(undeclared.exit_code, 2) << undeclared.output;
  EXPECT_NE(undeclared.output.find("argument --channels: this program declares no channels"), std::string::npos)
      << undeclared.output;
}

}  // namespace
}  // namespace rover::test
