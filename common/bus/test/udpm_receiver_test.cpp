// The udpm receiver (bus/udpm_receiver.hpp): crafted datagrams through Take, and messages
// a real LCM publishes on a real udpm bus (ctest runs in a private network namespace).
#include "bus/udpm_receiver.hpp"

#include "lcm_datagram.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <chrono>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace rover::bus {
namespace {

std::vector<std::uint8_t> Short(const std::string& channel, const std::vector<std::uint8_t>& payload) {
  return test::ShortDatagram(channel, payload);
}

// Fragment `number` of `count` of a long message `whole` cut into `piece`-byte pieces.
std::vector<std::uint8_t> Fragment(const std::string& channel, std::uint32_t seqno, const std::vector<std::uint8_t>& whole,
                                   int number, int count, std::size_t piece) {
  const std::size_t offset = static_cast<std::size_t>(number) * piece;
  const std::size_t end = std::min(whole.size(), offset + piece);
  return test::FragmentDatagram(channel, seqno, static_cast<std::uint32_t>(whole.size()),
                                static_cast<std::uint32_t>(offset), static_cast<std::uint16_t>(number),
                                static_cast<std::uint16_t>(count),
                                {whole.begin() + static_cast<std::ptrdiff_t>(offset),
                                 whole.begin() + static_cast<std::ptrdiff_t>(end)});
}

struct Got {
  std::vector<std::string> channels;
  std::vector<std::vector<std::uint8_t>> payloads;
  std::vector<std::int64_t> utimes;
  UdpmReceiver::Handler handler() {
    return [this](const std::string& c, const std::uint8_t* p, std::size_t n, std::int64_t utime) {
      utimes.push_back(utime);
      channels.push_back(c);
      payloads.emplace_back(p, p + n);
    };
  }
};

// A port free on this machine now (bound and closed again).
int FreePort() {
  const int fd = socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  EXPECT_EQ(bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
  socklen_t size = sizeof a;
  getsockname(fd, reinterpret_cast<sockaddr*>(&a), &size);
  close(fd);
  return ntohs(a.sin_port);
}

TEST(UdpmReceiver, ShortMessagesAndWhatIsNotLcmsAreToldApart) {
  UdpmReceiver r("udpm://239.255.76.67:" + std::to_string(FreePort()) + "?ttl=0");
  Got got;
  EXPECT_TRUE(r.Take(Short("SIM_SYNC", {1, 2, 3}).data(), Short("SIM_SYNC", {1, 2, 3}).size(), 1, got.handler()));
  const auto empty = Short("A", {});
  EXPECT_TRUE(r.Take(empty.data(), empty.size(), 1, got.handler()));
  ASSERT_EQ(got.channels, (std::vector<std::string>{"SIM_SYNC", "A"}));
  EXPECT_EQ(got.payloads[0], (std::vector<std::uint8_t>{1, 2, 3}));
  EXPECT_TRUE(got.payloads[1].empty());
  EXPECT_EQ(r.malformed(), 0);
  // Not LCM's magic, too short, a channel with no terminator, an empty channel name.
  const std::vector<std::uint8_t> junk = {'H', 'T', 'T', 'P', ' ', '1', '.', '1', ' ', '2'};
  EXPECT_FALSE(r.Take(junk.data(), junk.size(), 1, got.handler()));
  auto unterminated = Short(std::string(80, 'X'), {});
  unterminated.pop_back();
  EXPECT_FALSE(r.Take(unterminated.data(), unterminated.size(), 1, got.handler()));
  EXPECT_FALSE(r.Take(unterminated.data(), 6, 1, got.handler()));
  const auto nameless = Short("", {9});
  EXPECT_FALSE(r.Take(nameless.data(), nameless.size(), 1, got.handler()));
  EXPECT_EQ(r.malformed(), 4);
  EXPECT_EQ(got.channels.size(), 2u);
}

TEST(UdpmReceiver, ALongMessageIsWholeOnlyWhenEveryFragmentHasCome) {
  UdpmReceiver r("udpm://239.255.76.67:" + std::to_string(FreePort()) + "?ttl=0");
  std::vector<std::uint8_t> whole(2500);
  for (std::size_t i = 0; i < whole.size(); ++i) whole[i] = static_cast<std::uint8_t>(i * 7 + 3);
  Got got;
  const auto f0 = Fragment("IMAGE", 5, whole, 0, 3, 1000), f1 = Fragment("IMAGE", 5, whole, 1, 3, 1000),
             f2 = Fragment("IMAGE", 5, whole, 2, 3, 1000);
  EXPECT_FALSE(r.Take(f1.data(), f1.size(), 1, got.handler()));  // before its first fragment: dropped
  EXPECT_EQ(r.malformed(), 1);
  EXPECT_FALSE(r.Take(f0.data(), f0.size(), 1, got.handler()));
  EXPECT_FALSE(r.Take(f2.data(), f2.size(), 1, got.handler()));
  EXPECT_FALSE(r.Take(f2.data(), f2.size(), 1, got.handler()));  // a duplicate counts once
  // Another sender's fragments do not mix in.
  const auto other = Fragment("IMAGE", 5, whole, 1, 3, 1000);
  EXPECT_FALSE(r.Take(other.data(), other.size(), 2, got.handler()));
  EXPECT_TRUE(got.channels.empty());
  EXPECT_TRUE(r.Take(f1.data(), f1.size(), 1, got.handler()));
  ASSERT_EQ(got.channels, std::vector<std::string>{"IMAGE"});
  EXPECT_EQ(got.payloads[0], whole);
  // A fragment that claims bytes past its message's end is refused, not copied.
  const auto first = Fragment("IMAGE", 6, whole, 0, 3, 1000);
  EXPECT_FALSE(r.Take(first.data(), first.size(), 1, got.handler()));
  auto beyond = Fragment("IMAGE", 6, whole, 2, 3, 1000);
  beyond[15] = 0xF0;  // offset 2032: its 500 bytes would end at 2532, past the 2500
  const std::int64_t before = r.malformed();
  EXPECT_FALSE(r.Take(beyond.data(), beyond.size(), 1, got.handler()));
  EXPECT_EQ(r.malformed(), before + 1);
  EXPECT_EQ(got.channels.size(), 1u);
}

// What LCM itself publishes, short and fragmented, comes out byte for byte.
TEST(UdpmReceiver, ReadsWhatARealLcmPublishes) {
  const std::string url = "udpm://239.255.76.67:" + std::to_string(FreePort()) + "?ttl=0&recv_buf_size=4194304";
  UdpmReceiver r(url);
  lcm::LCM publisher(url);
  ASSERT_TRUE(publisher.good());
  std::vector<std::uint8_t> small = {10, 20, 30}, large(200000);
  for (std::size_t i = 0; i < large.size(); ++i) large[i] = static_cast<std::uint8_t>(i * 31 + i / 256);
  ASSERT_EQ(publisher.publish("SIM_SYNC", small.data(), static_cast<unsigned>(small.size())), 0);
  ASSERT_EQ(publisher.publish("BIG", large.data(), static_cast<unsigned>(large.size())), 0);
  Got got;
  for (int i = 0; i < 100 && got.channels.size() < 2; ++i) {
    pollfd p{r.fd(), POLLIN, 0};
    if (poll(&p, 1, 100) > 0) r.Drain(got.handler());
  }
  ASSERT_EQ(got.channels, (std::vector<std::string>{"SIM_SYNC", "BIG"}));
  EXPECT_EQ(got.payloads[0], small);
  EXPECT_EQ(got.payloads[1], large);
  EXPECT_EQ(r.malformed(), 0);
  // Stamped when they came, in wall microseconds, as LCM's recv_utime.
  const auto now = std::chrono::duration_cast<std::chrono::microseconds>(
                       std::chrono::system_clock::now().time_since_epoch()).count();
  for (const std::int64_t t : got.utimes) {
    EXPECT_GT(t, now - 10'000'000);
    EXPECT_LE(t, now);
  }
}

TEST(UdpmReceiver, AnotherProviderIsAOneLineError) {
  EXPECT_EQ(UdpmGroupAndPort("udpm://239.255.76.67:7701?ttl=0"), std::make_pair(std::string("239.255.76.67"), 7701));
  EXPECT_EQ(UdpmGroupAndPort("udpm://"), std::make_pair(std::string("239.255.76.67"), 7667));
  EXPECT_EQ(UdpmGroupAndPort("memq://").second, -1);
  try {
    UdpmReceiver r("memq://");
    FAIL() << "memq:// opened";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("cannot receive on the bus at memq://"), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos);
  }
}

}  // namespace
}  // namespace rover::bus
