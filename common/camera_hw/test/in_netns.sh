#!/bin/sh
# Runs "$@" in a new user and network namespace whose only interface is a loopback with
# 127.0.0.1 and 127.0.0.2 (one fake camera on each), so that Aravis's discovery broadcasts
# and the fake cameras' traffic never leave the machine. Exit 77 (ctest: skipped) where
# namespaces cannot be made.
unshare -rn true 2>/dev/null || { echo "camera_hw: cannot make a network namespace (unshare -rn): skipped"; exit 77; }
# (The multicast route lets a test that runs camera_capture hear it on an LCM bus there.)
exec unshare -rn sh -c 'ip link set lo up && ip addr add 127.0.0.2/8 dev lo && ip route add 224.0.0.0/4 dev lo &&
  exec "$@"' sh \
  env ROVER_CAMERA_NETNS=1 "$@"
