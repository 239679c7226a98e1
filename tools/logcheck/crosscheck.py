#!/usr/bin/env python3
"""An independent second reader of an LCM log's completeness, for checking logcheck.

It shares no code with the project: it parses the LCM log file format itself (each event:
sync word 0xEDA1DA01, event number, timestamp, channel length, data length, channel,
data) and the first bytes of each message (8-byte type fingerprint, then int64 utime and,
except on HEARTBEAT, int64 pub_seq = publisher id << 32 | count; a heartbeat has a string
process name and then int64 seq). A count that skips is a lost message; a count back at 0
is a restart. Prints the messages, lost count and gaps, and exits 1 if anything was lost.

    python3 tools/logcheck/crosscheck.py out/demo/log.lcm
"""
import struct
import sys


def events(path):
    with open(path, "rb") as f:
        data = f.read()
    pos = 0
    while pos + 28 <= len(data):
        sync, _num, _ts, clen, dlen = struct.unpack_from(">IqqII", data, pos)
        if sync != 0xEDA1DA01:
            raise SystemExit(f"{path}: bad sync word at byte {pos}")
        pos += 28
        channel = data[pos:pos + clen].decode()
        pos += clen
        yield channel, data[pos:pos + dlen]
        pos += dlen


def key_and_count(channel, msg):
    if channel == "HEARTBEAT":
        (slen,) = struct.unpack_from(">i", msg, 16)
        name = msg[20:20 + slen - 1].decode(errors="replace")
        (seq,) = struct.unpack_from(">q", msg, 20 + slen)
        return (channel, name), seq
    (pub_seq,) = struct.unpack_from(">q", msg, 16)
    return (channel, (pub_seq >> 32) & 0xFFFFFFFF), pub_seq & 0xFFFFFFFF


def main():
    if len(sys.argv) != 2:
        raise SystemExit("usage: crosscheck.py LOG.lcm")
    last, total, lost, gaps = {}, 0, 0, []
    for channel, msg in events(sys.argv[1]):
        if channel == "LCM_SELF_TEST":  # LCM's own start-up probe, not a project message
            continue
        total += 1
        if len(msg) < 24:
            raise SystemExit(f"{channel}: a message of {len(msg)} bytes has no utime and count")
        key, count = key_and_count(channel, msg)
        if key in last and count != last[key] + 1 and count != 0:
            missing = count - last[key] - 1
            if missing > 0:
                lost += missing
                gaps.append(f"{key[0]} publisher {key[1]}: {missing} lost after count {last[key]}")
        elif key not in last and count != 0:
            lost += count
            gaps.append(f"{key[0]} publisher {key[1]}: first count {count} (the first {count} lost)")
        last[key] = count
    for g in gaps:
        print(g)
    print(f"{total} messages, {lost} lost, {len(gaps)} gaps")
    sys.exit(1 if lost else 0)


if __name__ == "__main__":
    main()
