#!/bin/sh
# with-veth IFACE PEER COMMAND...: makes the veth pair IFACE/PEER in this
# network namespace (both up; kept if it exists), then runs COMMAND.
# An EtherCAT line in a container: `ethercat serve --iface IFACE` on one
# end, the master on PEER, both in the same namespace (a pod, or a compose
# service and one with network_mode: service:...). Needs CAP_NET_ADMIN.
set -eu
iface=$1 peer=$2
shift 2
if ! ip link show "$iface" >/dev/null 2>&1; then
    ip link add "$iface" type veth peer name "$peer"
fi
ip link set "$iface" up
ip link set "$peer" up
exec "$@"
