// The kernel's channel filter (bus/kernel_filter.hpp): crafted LCM datagrams sent to a real
// UDP socket on the loopback, and a Bus on a real udpm bus.
#include "bus/kernel_filter.hpp"

#include "bus/bus.hpp"
#include "lcm_datagram.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <gtest/gtest.h>
#include <rover_msgs/heartbeat_t.hpp>

#include <cstdint>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace rover::bus {
namespace {

// LCM's short message: the payload is the datagram's marker, so the receiver can tell which
// came.
std::vector<std::uint8_t> Short(const std::string& channel, std::uint8_t marker) {
  return test::ShortDatagram(channel, {marker});
}

// A fragment of a long message (LC03); only fragment 0 names the channel.
std::vector<std::uint8_t> Fragment(const std::string& channel, std::uint16_t number, std::uint8_t marker) {
  return test::FragmentDatagram(channel, 9, 100000, number * 1000u, number, 3, {marker});
}

class Socket {
 public:
  Socket() : fd_(socket(AF_INET, SOCK_DGRAM, 0)) {
    if (fd_ < 0) throw std::runtime_error("socket");
  }
  ~Socket() { close(fd_); }
  int fd() const { return fd_; }
  int BindLoopback() {
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (bind(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) throw std::runtime_error("bind");
    socklen_t len = sizeof a;
    getsockname(fd_, reinterpret_cast<sockaddr*>(&a), &len);
    return ntohs(a.sin_port);
  }
  void SendTo(int port, const std::vector<std::uint8_t>& d) {
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(static_cast<std::uint16_t>(port));
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ASSERT_EQ(sendto(fd_, d.data(), d.size(), 0, reinterpret_cast<sockaddr*>(&a), sizeof a),
              static_cast<ssize_t>(d.size()));
  }
  // The markers of every datagram waiting (their last byte).
  std::set<int> Drain() {
    std::set<int> markers;
    std::uint8_t buf[2048];
    for (;;) {
      const ssize_t n = recv(fd_, buf, sizeof buf, MSG_DONTWAIT);
      if (n <= 0) break;
      markers.insert(buf[n - 1]);
    }
    return markers;
  }

 private:
  int fd_;
};

TEST(KernelFilter, KeepsTheSubscribedChannelsAndWhatNamesNone) {
  Socket rx, tx;
  const int port = rx.BindLoopback();
  ASSERT_TRUE(AttachFilter(rx.fd(), ChannelFilterProgram({"POSE", "IMU", "STEREO_FRAME"})));
  tx.SendTo(port, Short("POSE", 1));            // kept
  tx.SendTo(port, Short("SIM_TRUTH", 2));       // dropped
  tx.SendTo(port, Short("POSE_X", 3));          // dropped: a longer name that begins alike
  tx.SendTo(port, Short("POS", 4));             // dropped: a shorter one
  tx.SendTo(port, Short("IMU", 5));             // kept (a name of 3 bytes and NUL: one word)
  tx.SendTo(port, Fragment("STEREO_FRAME", 0, 6));  // kept: its first fragment
  tx.SendTo(port, Fragment("HAZCAM_FRAME", 0, 7));  // dropped
  tx.SendTo(port, Fragment("", 1, 8));              // kept: a later fragment names no channel
  tx.SendTo(port, {'n', 'o', 't', ' ', 'L', 'C', 'M', 9});  // kept: LCM judges what is not its own
  tx.SendTo(port, {0x4c, 0x43, 10});                // dropped: shorter than the magic it is read for
  EXPECT_EQ(rx.Drain(), (std::set<int>{1, 5, 6, 8, 9}));
  // Taken off, everything comes.
  ASSERT_TRUE(AttachFilter(rx.fd(), {}));
  tx.SendTo(port, Short("SIM_TRUTH", 2));
  EXPECT_EQ(rx.Drain(), (std::set<int>{2}));
}

TEST(KernelFilter, NamesOfEveryLengthMatchOnlyThemselves) {
  // Lengths 1 to 9 take every mix of word, half-word and byte loads.
  std::vector<std::string> names;
  for (int n = 1; n <= 9; ++n) names.push_back(std::string(static_cast<std::size_t>(n), 'A' + n));
  Socket rx, tx;
  const int port = rx.BindLoopback();
  ASSERT_TRUE(AttachFilter(rx.fd(), ChannelFilterProgram(names)));
  std::set<int> expected;
  for (int n = 1; n <= 9; ++n) {
    const std::string name = names[static_cast<std::size_t>(n - 1)];
    tx.SendTo(port, Short(name, static_cast<std::uint8_t>(n)));
    expected.insert(n);
    std::string off_by_last = name;
    off_by_last.back() = 'z';
    tx.SendTo(port, Short(off_by_last, static_cast<std::uint8_t>(100 + n)));
    tx.SendTo(port, Short(name + "z", static_cast<std::uint8_t>(150 + n)));
  }
  EXPECT_EQ(rx.Drain(), expected);
}

TEST(KernelFilter, PatternsAndOtherProvidersAreNotFiltered) {
  EXPECT_THROW(ChannelFilterProgram({"POSE", ".*"}), std::invalid_argument);
  EXPECT_FALSE(PlainChannel("HEART.*"));
  EXPECT_FALSE(PlainChannel("A|B"));
  EXPECT_TRUE(PlainChannel("STEREO_FRAME"));
  EXPECT_EQ(UdpmPort("udpm://239.255.76.67:7667?ttl=0&recv_buf_size=8388608"), 7667);
  EXPECT_EQ(UdpmPort("udpm://239.255.76.67:7701"), 7701);
  EXPECT_EQ(UdpmPort("udpm://239.255.76.67"), 7667);
  EXPECT_EQ(UdpmPort("memq://"), -1);
  EXPECT_EQ(UdpmPort("udpm://239.255.76.67:x?ttl=0"), -1);
}

// A Bus on a real udpm bus: the filter follows its subscriptions, and a pattern takes it off.
TEST(KernelFilter, ABusFiltersItsSubscriptionsUntilOneIsAPattern) {
  int port = 0;
  {
    Socket probe;
    port = probe.BindLoopback();  // a port free on this machine, closed again for LCM
  }
  Bus bus("udpm://239.255.76.67:" + std::to_string(port) + "?ttl=0");
  bus.FilterInKernel(true);
  EXPECT_FALSE(bus.filtered_in_kernel());  // nothing subscribed yet
  bus.Subscribe<rover_msgs::heartbeat_t>("HEARTBEAT", [](const rover_msgs::heartbeat_t&) {});
  EXPECT_TRUE(bus.filtered_in_kernel());
  bus.Subscribe<rover_msgs::heartbeat_t>("HEART.*", [](const rover_msgs::heartbeat_t&) {});
  EXPECT_FALSE(bus.filtered_in_kernel());
  Bus off("udpm://239.255.76.67:" + std::to_string(port + 1) + "?ttl=0");
  off.Subscribe<rover_msgs::heartbeat_t>("HEARTBEAT", [](const rover_msgs::heartbeat_t&) {});
  EXPECT_FALSE(off.filtered_in_kernel());  // not asked for
}

// The drop counts of the sockets bound to `port` (from /proc/net/udp; one entry a socket).
std::vector<long> DropsOnPort(int port) {
  std::ifstream in("/proc/net/udp");
  std::string line;
  std::getline(in, line);  // the header
  std::vector<long> drops;
  char want[8];
  std::snprintf(want, sizeof want, ":%04X", port);
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::string slot, local, word;
    fields >> slot >> local;
    if (local.size() < 5 || local.substr(local.size() - 5) != want) continue;
    while (fields >> word) {}
    drops.push_back(std::stol(word));  // the last column
  }
  return drops;
}

// A bus that reads its own socket takes LCM's receive socket off the group: the kernel no
// longer copies every datagram to it for its drop-all filter (which counted each as a drop).
TEST(KernelFilter, ABusReadingItsOwnSocketLeavesLcmsSocketOutOfTheGroup) {
  int port = 0;
  {
    Socket probe;
    port = probe.BindLoopback();
  }
  const std::string url = "udpm://239.255.76.67:" + std::to_string(port) + "?ttl=0";
  Bus bus(url);
  bus.ReadOwnSocket();
  int heard = 0;
  bus.Subscribe<rover_msgs::heartbeat_t>("HEARTBEAT", [&heard](const rover_msgs::heartbeat_t&) { ++heard; });
  Bus publisher(url);
  for (int i = 0; i < 5; ++i) {
    rover_msgs::heartbeat_t hb{};
    hb.process = "test";
    hb.seq = i;
    publisher.Publish("HEARTBEAT", hb);
  }
  for (int i = 0; i < 100 && heard < 5; ++i) bus.Handle(50);
  EXPECT_EQ(heard, 5);
  // The bus's own socket, LCM's beside it, and the publisher's LCM receive socket.
  const std::vector<long> drops = DropsOnPort(port);
  ASSERT_GE(drops.size(), 2u);
  for (const long d : drops) EXPECT_EQ(d, 0) << "a socket on port " << port << " dropped datagrams";
}

}  // namespace
}  // namespace rover::bus
