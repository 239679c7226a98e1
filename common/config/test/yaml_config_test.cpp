#include "config/yaml_config.hpp"

#include <gtest/gtest.h>

#include <functional>

using rover::config::ConfigError;
using rover::config::ConfigNode;

namespace {

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(ConfigNode, ReadsValuesAndKeepsDefaults) {
  auto root = ConfigNode::FromString("vo:\n  iters: 7\n  scale: 0.5\n  name: x\n", "t.yaml");
  int iters = 1;
  double scale = 1.0, absent = 3.0;
  std::string name;
  root["vo"].Get("iters", iters, 1, 100);
  root["vo"].Get("scale", scale);
  root["vo"].Get("absent", absent);
  root["vo"].Get("name", name);
  EXPECT_EQ(iters, 7);
  EXPECT_DOUBLE_EQ(scale, 0.5);
  EXPECT_DOUBLE_EQ(absent, 3.0);
  EXPECT_EQ(name, "x");
}

TEST(ConfigNode, ErrorNamesFileKeyAndExpectation) {
  auto root = ConfigNode::FromString("vo:\n  iters: abc\n", "configs/vo.yaml");
  int iters = 1;
  const std::string msg = ErrorOf([&] { root["vo"].Get("iters", iters, 1, 100); });
  EXPECT_EQ(msg, "configs/vo.yaml: vo.iters: expected an integer in [1, 100], got \"abc\"");
}

TEST(ConfigNode, RejectsOutOfRangeNanAndUnknownKeys) {
  auto root = ConfigNode::FromString("a: 5\nb: .nan\nc: 1\n", "f.yaml");
  double a = 0, b = 0;
  EXPECT_NE(ErrorOf([&] { root.Get("a", a, 0.0, 1.0); }).find("f.yaml: a: expected"),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] { root.Get("b", b); }).find("finite"), std::string::npos);
  EXPECT_NE(ErrorOf([&] { root.CheckKeys({"a", "b"}); }).find("f.yaml: c: unknown key"),
            std::string::npos);
}

TEST(ConfigNode, ReportsSyntaxErrorsWithLine) {
  const std::string msg = ErrorOf([] { ConfigNode::FromString("a: [1, 2\nb: 3\n", "bad.yaml"); });
  EXPECT_EQ(msg.rfind("bad.yaml:", 0), 0u) << msg;
  EXPECT_NE(msg.find("invalid YAML"), std::string::npos);
}

TEST(ConfigNode, MissingFileIsOneLineError) {
  const std::string msg = ErrorOf([] { ConfigNode::LoadFile("/nonexistent/x.yaml"); });
  EXPECT_EQ(msg, "/nonexistent/x.yaml: cannot open file (expected a readable YAML file)");
}

TEST(ConfigNode, VectorsAndEnums) {
  auto root = ConfigNode::FromString("v: [1, 2, 3]\nmode: fast\n", "f.yaml");
  std::vector<double> v;
  root.Get("v", v, 3);
  EXPECT_EQ(v, (std::vector<double>{1, 2, 3}));
  EXPECT_NE(ErrorOf([&] { root.Get("v", v, 2); }).find("expected a list of 2 numbers"),
            std::string::npos);
  std::string mode;
  EXPECT_NE(ErrorOf([&] { root.GetEnum("mode", mode, {"slow", "safe"}); })
                .find("expected one of: slow, safe"),
            std::string::npos);
}
