// Channels a process does not subscribe to, dropped by the kernel before they wake it.
//
// LCM's udpm provider puts every channel on one multicast group and port, so every
// process's socket receives every datagram, and LCM's receive thread wakes for each, reads
// it, and throws away those no handler wants. On the shared 2-core machine those wake-ups
// are most of what a process costs that is not its own work: in a demo run the set made
// about 145,000 voluntary context switches for 2,330 instants, each process's receive
// thread about 4 a tick whatever it subscribed to (docs/SIMTIME_LOG.md, "Datagrams nobody
// asked for"). A classic BPF socket filter (SO_ATTACH_FILTER) on the process's LCM socket
// keeps only the datagrams whose channel it subscribes to, so the kernel neither queues
// nor wakes for the rest; what is delivered is exactly what LCM would have dispatched.
//
// Written here because LCM has no such option: it exposes neither its receive socket nor
// a filter, so the socket is found by its bound port (FindUdpSocket).
#pragma once

#include <linux/filter.h>

#include <string>
#include <vector>

namespace rover::bus {

// The UDP port of an LCM udpm URL ("udpm://239.255.76.67:7667?ttl=0"; LCM's 7667 when it
// names none), or -1 for another provider or a port that is not a number.
int UdpmPort(const std::string& url);

// Whether `channel` is a plain name, not one of LCM's regular expressions (".*", "A|B"):
// only plain names can be matched byte for byte in the kernel.
bool PlainChannel(const std::string& channel);

// The filter program over an LCM datagram as a UDP socket filter sees it (the UDP header,
// then LCM's): a short message (magic LC02) or the first fragment of a long one (LC03,
// fragment 0) is kept when its channel, with its terminating NUL, is one of `channels`;
// a later fragment (it names no channel) and anything without LCM's magic are kept, for
// LCM to judge. Throws std::invalid_argument for a channel that is not plain or is over
// 255 bytes.
std::vector<sock_filter> ChannelFilterProgram(const std::vector<std::string>& channels);

// The one UDP socket of this process bound to `port` (IPv4), or -1 when there is none or
// more than one (then which is whose cannot be told).
int FindUdpSocket(int port);

// Attaches `program` to socket `fd` (replacing any filter), or detaches when empty. False,
// with errno, when the kernel refuses.
bool AttachFilter(int fd, const std::vector<sock_filter>& program);

}  // namespace rover::bus
