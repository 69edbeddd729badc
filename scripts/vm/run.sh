#!/usr/bin/env bash
# Boots the CAN test VM (scripts/vm/build.sh first) under QEMU/TCG: the raw vmlinux via its PVH
# entry, the initramfs whose /init is tests/vm/guest.sh, two emulated Kvaser PCI cards (SJA1000)
# on one QEMU can-bus, the host's filesystem shared read-only over 9p (for the python-canopen
# scenarios). Prints what it checks, saves the serial console to target/vm/serial.log,
# and fails unless the guest reported "VMTEST-EXIT 0" and every scenario passed.
set -euo pipefail
cd "$(dirname "$0")/../.."
VM=target/vm
[ -f "$VM/vmlinux" ] && [ -f "$VM/initramfs.cpio.gz" ] || bash scripts/vm/build.sh
echo "vm: boots Debian $(ls $VM/kernel/lib/modules) under TCG and checks, on real Linux SocketCAN:"
echo "vm:   vcan0..3: ttctl drives 8 ttdrive-sim axes (4 channels × 2) through the gantry6 stroke"
echo "vm:     (tracking bound, no missed feedback, no bad frame, latency statistics);"
echo "vm:   EMCY, a drive leaving Operation Enabled, malformed TPDOs → controlled stop of every axis;"
echo "vm:   emulated Kvaser pair at 1 Mbit/s: the stroke, and an unplugged drive → controlled stop;"
echo "vm:   a configuration over the bus budget refused;"
echo "vm:   vcan4/5 with python-canopen (the host's Python over a read-only 9p share): python-canopen"
echo "vm:     masters ttdrive-sim (SDO, CiA 402, PDO remap, CSP), ttctl masters a LocalNode from a vendor EDS."
log=$VM/serial.log
status=0
timeout "${VM_TIMEOUT:-480}" qemu-system-x86_64 \
    -machine pc -accel tcg -cpu max -smp 2 -m 512 \
    -nographic -no-reboot \
    -kernel "$VM/vmlinux" -initrd "$VM/initramfs.cpio.gz" \
    -append "console=ttyS0 panic=-1 quiet loglevel=3" \
    -object can-bus,id=canbus0 \
    -device kvaser_pci,canbus=canbus0 -device kvaser_pci,canbus=canbus0 \
    -virtfs local,path=/,mount_tag=hostfs,security_model=none,readonly=on \
    > "$log" 2>&1 || status=$?
grep -E "^(VMTEST|VMSTATS|\[)" "$log" | tr -d '\r' || true
if [ $status -ne 0 ]; then
    echo "vm: QEMU exited with status $status (timeout 124); serial log: $log"
    exit 1
fi
if ! grep -q "VMTEST-EXIT 0" "$log"; then
    echo "vm: FAILED (serial log: $log)"
    exit 1
fi
if grep -q "VMTEST .* FAIL" "$log"; then
    echo "vm: FAILED"
    exit 1
fi
echo "vm: all scenarios passed"
