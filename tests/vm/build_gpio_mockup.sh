#!/bin/bash
# Host side of the VM scenario gpio (a ctest fixture): builds the kernel's own gpio-mockup driver as
# a module for the guest kernel. Debian's kernel leaves GPIO_MOCKUP and GPIO_SIM out, so there is no
# gpiochip to test libgpiod against, not even in the VM. The driver's source comes from Debian's
# linux-source package, built against the guest kernel's linux-headers package (both installed by
# scripts/install-deps). It needs the kernel's irq_sim, which Debian's kernel does not build either, so
# irq_sim.c is linked into the same module; irq_to_desc() is not exported to modules, so its one call
# becomes generic_handle_irq(), which does the same lookup.
#   build_gpio_mockup.sh OUT_DIR   (writes OUT_DIR/gpio-mockup.ko)
set -euo pipefail
OUT=$(realpath -m "$1")
kver=$(ls /lib/modules | grep -E -- '-amd64$' | sort -V | tail -1 || true)  # the kernel run-vm boots
src=$(ls /usr/src/linux-source-*.tar.xz 2>/dev/null | sort -V | tail -1 || true)
if [ -z "$kver" ] || [ ! -d "/lib/modules/$kver/build" ]; then
  echo "build_gpio_mockup: no headers for the guest kernel ${kver:-?} (/lib/modules/$kver/build); run scripts/install-deps" >&2
  exit 1
fi
if [ -z "$src" ]; then
  echo "build_gpio_mockup: no kernel source (/usr/src/linux-source-*.tar.xz); run scripts/install-deps" >&2
  exit 1
fi
top=$(basename "$src" .tar.xz)
rm -rf "$OUT"
mkdir -p "$OUT/src"
tar -xJf "$src" -C "$OUT/src" --strip-components=3 \
  "$top/drivers/gpio/gpio-mockup.c" "$top/drivers/gpio/gpiolib.h" "$top/kernel/irq/irq_sim.c"
cd "$OUT/src"
mv gpio-mockup.c gpio-mockup-main.c
grep -q 'handle_simple_irq(irq_to_desc(irqnum));' irq_sim.c
sed -i 's/handle_simple_irq(irq_to_desc(irqnum));/generic_handle_irq(irqnum);/' irq_sim.c
printf 'obj-m := gpio-mockup.o\ngpio-mockup-y := gpio-mockup-main.o irq_sim.o\n' > Kbuild
make -s -C "/lib/modules/$kver/build" M="$PWD" modules 2>&1 | grep -v 'Skipping BTF generation' || true
test -f gpio-mockup.ko
cp gpio-mockup.ko "$OUT/"
echo "built $OUT/gpio-mockup.ko for $kver from $(basename "$src")"
