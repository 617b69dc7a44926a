#!/bin/bash
# Host side of the VM scenarios that need a driver Debian's kernel does not ship (ctest fixtures):
# builds it as a module for the guest kernel (the kernel run-vm boots) against that kernel's
# linux-headers package; scripts/install-deps installs the headers and the sources.
#   build_guest_module.sh MODULE OUT_DIR   (writes OUT_DIR/MODULE.ko)
#
# gpio-mockup (scenario_gpio.sh): Debian's kernel leaves GPIO_MOCKUP and GPIO_SIM out, so there is no
# gpiochip to test libgpiod against, not even in the VM. The driver's source comes from Debian's
# linux-source package. It needs the kernel's irq_sim, which Debian's kernel does not build either, so
# irq_sim.c is linked into the same module; irq_to_desc() is not exported to modules, so its one call
# becomes generic_handle_irq(), which does the same lookup.
#
# v4l2loopback (scenario_camerad_mjpeg.sh): a V4L2 device fed from user space, the only way to give
# camerad MJPEG frames from a kernel driver (vivid has no compressed formats). Its source comes from
# Debian's v4l2loopback-source package (0.12.7).
set -euo pipefail
module=$1
OUT=$(realpath -m "$2")
kver=$(ls /lib/modules | grep -E -- '-amd64$' | sort -V | tail -1 || true)  # the kernel run-vm boots
if [ -z "$kver" ] || [ ! -d "/lib/modules/$kver/build" ]; then
  echo "build_guest_module: no headers for the guest kernel ${kver:-?} (/lib/modules/$kver/build); run scripts/install-deps" >&2
  exit 1
fi
# need FILE PACKAGE: the source FILE, or a line naming the package that brings it.
need() {
  if [ -z "$1" ] || [ ! -f "$1" ]; then
    echo "build_guest_module: no source for $module (package $2); run scripts/install-deps" >&2
    exit 1
  fi
}
rm -rf "$OUT"
mkdir -p "$OUT/src"
cd "$OUT/src"
case "$module" in
  gpio-mockup)
    src=$(ls /usr/src/linux-source-*.tar.xz 2>/dev/null | sort -V | tail -1 || true)
    need "$src" linux-source
    top=$(basename "$src" .tar.xz)
    tar -xJf "$src" --strip-components=3 \
      "$top/drivers/gpio/gpio-mockup.c" "$top/drivers/gpio/gpiolib.h" "$top/kernel/irq/irq_sim.c"
    mv gpio-mockup.c gpio-mockup-main.c
    grep -q 'handle_simple_irq(irq_to_desc(irqnum));' irq_sim.c
    sed -i 's/handle_simple_irq(irq_to_desc(irqnum));/generic_handle_irq(irqnum);/' irq_sim.c
    printf 'obj-m := gpio-mockup.o\ngpio-mockup-y := gpio-mockup-main.o irq_sim.o\n' > Kbuild
    ;;
  v4l2loopback)
    src=/usr/src/v4l2loopback.tar.bz2
    need "$src" v4l2loopback-source
    tar -xjf "$src" --strip-components=2 modules/v4l2loopback/v4l2loopback.c \
      modules/v4l2loopback/v4l2loopback_formats.h
    printf 'obj-m := v4l2loopback.o\n' > Kbuild
    ;;
  *)
    echo "build_guest_module: unknown module '$module' (gpio-mockup, v4l2loopback)" >&2
    exit 2
    ;;
esac
make -s -C "/lib/modules/$kver/build" M="$PWD" modules 2>&1 | grep -v 'Skipping BTF generation' || true
test -f "$module.ko"
cp "$module.ko" "$OUT/"
echo "built $OUT/$module.ko for $kver from $(basename "$src")"
