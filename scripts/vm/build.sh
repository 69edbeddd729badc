#!/usr/bin/env bash
# Builds the VM for the CAN tests (idempotent, cached under target/vm/): a Debian 6.1 kernel
# (apt-get download + dpkg-deb -x, never installed), its CAN modules with a depmod'ed modules.dep,
# and an initramfs with busybox, iproute2's ip, can-utils' candump/cangen, the release binaries
# ttctl and ttdrive-sim (with every library ldd names), their configurations, the gantry6 stroke
# written by ttmanip.ctl and the guest scenario script tests/vm/guest.sh; the 9p modules with which
# the guest mounts the host's filesystem (scripts/vm/run.sh shares it read-only) to run the
# python-canopen scenarios (tests/vm/interop.py) with the host's Python.
set -euo pipefail
cd "$(dirname "$0")/../.."
ROOT=$PWD
VM=$ROOT/target/vm
mkdir -p "$VM"

# 1. host packages
need=()
command -v qemu-system-x86_64 >/dev/null || need+=(qemu-system-x86)
dpkg -s busybox-static >/dev/null 2>&1 || need+=(busybox-static)
command -v candump >/dev/null || need+=(can-utils)
command -v depmod >/dev/null || need+=(kmod)
[ -x /usr/sbin/ip ] || [ -x /sbin/ip ] || need+=(iproute2)
command -v cpio >/dev/null || need+=(cpio)
if [ ${#need[@]} -gt 0 ]; then
    echo "vm/build: apt-get install ${need[*]}"
    SUDO=""; [ "$(id -u)" = 0 ] || SUDO=sudo
    $SUDO apt-get update -q >/dev/null
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q "${need[@]}" >/dev/null
fi
BUSYBOX=$(command -v busybox)

# 2. kernel: newest linux-image-6.1.0-N-amd64 (not -cloud: no CAN; not -rt)
if [ ! -f "$VM/vmlinux" ] || [ ! -d "$VM/kernel/lib/modules" ]; then
    pkg=$(apt-cache search --names-only '^linux-image-6\.1\.0-[0-9]+-amd64$' | awk '{print $1}' | sort -V | tail -1)
    [ -n "$pkg" ] || { echo "vm/build: no linux-image-6.1.0-*-amd64 in apt (run apt-get update)"; exit 1; }
    echo "vm/build: kernel $pkg"
    mkdir -p "$VM/deb"
    (cd "$VM/deb" && ls "$pkg"_*.deb >/dev/null 2>&1 || apt-get download "$pkg" 2>&1 | grep -v '^W: Download is performed unsandboxed' || true)
    rm -rf "$VM/kernel"
    dpkg-deb -x "$VM/deb/$pkg"_*.deb "$VM/kernel"
    # the raw vmlinux (PVH entry) boots in ~2.5 s under TCG: extract it from the xz/gzip/zstd vmlinuz
    python3 - "$VM/kernel/boot/"vmlinuz-* "$VM/vmlinux" <<'PY'
import gzip, lzma, sys
data = open(sys.argv[1], "rb").read()
for magic, dec in ((b"\xfd7zXZ\x00", lambda b: lzma.LZMADecompressor().decompress(b)),
                   (b"\x1f\x8b\x08", lambda b: gzip.decompress(b))):
    i = data.find(magic)
    while i >= 0:
        try:
            out = dec(data[i:])
            if out[:4] == b"\x7fELF":
                open(sys.argv[2], "wb").write(out)
                sys.exit(0)
        except Exception:
            pass
        i = data.find(magic, i + 1)
sys.exit("no vmlinux found in " + sys.argv[1])
PY
fi
KVER=$(ls "$VM/kernel/lib/modules" | head -1)

# 3. release binaries, the release profile as shipped: scripts/test.sh has built them for the Python
# tests already (one release build for both), so this is a no-op there
echo "vm/build: cargo build --release -p ttcan --bin ttctl --bin ttdrive-sim"
cargo build --release --quiet -p ttcan --bin ttctl --bin ttdrive-sim

# 4. the stroke, planned by the Python package
if [ -x "$ROOT/.venv/bin/python" ] && "$ROOT/.venv/bin/python" -c "import ttmanip.ctl" 2>/dev/null; then
    "$ROOT/.venv/bin/python" -m ttmanip.ctl "$VM/stroke.csv" >/dev/null
elif [ -s "$VM/stroke.csv" ]; then
    echo "vm/build: ttmanip not installed in .venv: reusing the stroke planned before ($VM/stroke.csv)"
else
    echo "vm/build: ttmanip not installed in .venv (scripts/setup.sh): cannot plan the stroke"; exit 1
fi

# 5. initramfs
IR=$VM/initramfs
rm -rf "$IR"
mkdir -p "$IR"/{bin,sbin,etc,proc,sys,dev,tmp,lib,lib64,usr/bin,ttmanip}
cp "$BUSYBOX" "$IR/bin/busybox"
for app in sh mount mkdir cat echo sleep poweroff modprobe insmod grep sed awk kill ls seq wc tail head cut tr date true false test printf chroot; do
    ln -sf busybox "$IR/bin/$app"
done
copy_with_libs() {  # copy binary $1 to $2 and every library ldd names
    cp "$1" "$2"
    ldd "$1" 2>/dev/null | awk '$2 == "=>" && $3 ~ /^\// {print $3} $1 ~ /^\// {print $1}' | while read -r lib; do
        [ -f "$lib" ] || continue
        mkdir -p "$IR$(dirname "$lib")"
        cp -L "$lib" "$IR$lib"
    done
}
IP=$(command -v ip)
copy_with_libs "$IP" "$IR/sbin/ip"
copy_with_libs "$(command -v candump)" "$IR/usr/bin/candump"
copy_with_libs "$(command -v cangen)" "$IR/usr/bin/cangen"
copy_with_libs "$ROOT/target/release/ttctl" "$IR/usr/bin/ttctl"
copy_with_libs "$ROOT/target/release/ttdrive-sim" "$IR/usr/bin/ttdrive-sim"
# modules: copy the CAN ones, build modules.dep with depmod on the copy
MD=$IR/lib/modules/$KVER
mkdir -p "$MD"
# can-bcm (python-can's periodic sends on SocketCAN: python-canopen's heartbeat) and 9p over virtio
# (issue 27: the guest runs the host's Python with python-canopen from a read-only
# share of the host's filesystem) and what it depends on
for m in net/can/can.ko net/can/can-raw.ko net/can/can-bcm.ko drivers/net/can/dev/can-dev.ko drivers/net/can/vcan.ko \
         drivers/net/can/sja1000/sja1000.ko drivers/net/can/sja1000/kvaser_pci.ko \
         drivers/virtio/virtio.ko drivers/virtio/virtio_ring.ko drivers/virtio/virtio_pci.ko \
         drivers/virtio/virtio_pci_legacy_dev.ko drivers/virtio/virtio_pci_modern_dev.ko \
         net/9p/9pnet.ko net/9p/9pnet_virtio.ko fs/netfs/netfs.ko fs/fscache/fscache.ko fs/9p/9p.ko; do
    src=$(ls "$VM/kernel/lib/modules/$KVER/kernel/$m"* | head -1)
    mkdir -p "$MD/kernel/$(dirname "$m")"
    cp "$src" "$MD/kernel/$(dirname "$m")/"
done
cp "$VM/kernel/lib/modules/$KVER/modules.builtin"* "$MD/" 2>/dev/null || true
cp "$VM/kernel/lib/modules/$KVER/modules.order" "$MD/" 2>/dev/null || true
depmod -b "$IR" "$KVER"
cp "$VM/stroke.csv" "$IR/ttmanip/stroke.csv"
cp "$ROOT"/tests/vm/*.toml "$IR/ttmanip/"
# the interoperability scenarios run the host's Python (with python-canopen, from the test extra)
# and these paths in a chroot on the host's filesystem
[ -x "$ROOT/.venv/bin/python" ] && "$ROOT/.venv/bin/python" -c "import canopen" \
    || { echo "vm/build: python-canopen not installed in .venv (scripts/setup.sh)"; exit 1; }
printf 'HOST_ROOT=%s\nHOST_PY=%s\n' "$ROOT" "$ROOT/.venv/bin/python" > "$IR/ttmanip/interop.env"
cp "$ROOT/tests/vm/guest.sh" "$IR/init"
chmod +x "$IR/init"
(cd "$IR" && find . | cpio -o -H newc --quiet | gzip -1 > "$VM/initramfs.cpio.gz")
echo "vm/build: $VM/vmlinux ($KVER), $VM/initramfs.cpio.gz ($(du -h "$VM/initramfs.cpio.gz" | cut -f1))"
