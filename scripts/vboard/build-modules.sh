#!/usr/bin/env bash
# Builds the two drivers the virtual board needs and Debian's kernel leaves out, out of tree
# against that kernel's headers (fetch-kernel.sh first), into its cache folder's modules/:
#   gpio-sim.ko   the simulated GPIO chip that carries the trigger line
#   vimc.ko       the virtual media controller camera (libcamera can drive it; vivid it cannot),
#                 with n_devs= for several instances (vimc-instances.c): one libcamera camera each
# Idempotent: modules already built for the kernel version are kept.
#
#   scripts/vboard/build-modules.sh amd64|arm64
set -euo pipefail
source "$(dirname "$0")/common.sh"
arch=${1:?usage: build-modules.sh amd64|arm64}
vboard_check_arch "$arch"

kver=$(vboard_kernel_version "$arch")
root=$(vboard_cache "$kver")
[[ -f $root/.complete-v1 ]] || {
  echo "build-modules: $root is missing: run scripts/vboard/fetch-kernel.sh $arch" >&2
  exit 1
}
out="$root/modules"
# The stamp names what the modules are: a newer recipe builds them again.
stamp=.modules-v2-vimc-instances
if [[ -f $out/$stamp ]]; then
  echo "build-modules: $out is complete"
  exit 0
fi
source_dir=$(vboard_cache "linux-source-$(cat "$root/source-version")")
kdir="$root/headers/usr/src/linux-headers-$kver"
make_args=(-C "$kdir" -j2)
if [[ $arch != "$(dpkg --print-architecture)" ]]; then
  make_args+=(ARCH=arm64 CROSS_COMPILE="$(vboard_cross_prefix "$arch")")
fi

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# gpio-sim selects IRQ_SIM, a built-in-only option Debian leaves off: the interrupt simulator
# is linked into the module instead. It calls irq_to_desc(), which modules cannot; the exported
# generic_handle_irq() reaches the same flow handler (handle_simple_irq).
mkdir "$work/gpio-sim"
cp "$source_dir/drivers/gpio/gpio-sim.c" "$work/gpio-sim/gpio-sim-main.c"
cp "$source_dir/drivers/gpio/gpiolib.h" "$source_dir/kernel/irq/irq_sim.c" "$work/gpio-sim/"
sed -i 's/handle_simple_irq(irq_to_desc(irqnum));/generic_handle_irq(irqnum);/' "$work/gpio-sim/irq_sim.c"
grep -q 'generic_handle_irq(irqnum);' "$work/gpio-sim/irq_sim.c" || {
  echo "build-modules: irq_sim.c has changed: the irq_to_desc() call was not found" >&2
  exit 1
}
printf 'obj-m := gpio-sim.o\ngpio-sim-y := gpio-sim-main.o irq_sim.o\n' >"$work/gpio-sim/Kbuild"

mkdir "$work/vimc"
cp "$source_dir"/drivers/media/test-drivers/vimc/*.[ch] "$work/vimc/"
# vimc registers one platform device: its own device and init/exit make way for n_devs of them.
core="$work/vimc/vimc-core.c"
grep -q '^static struct platform_device vimc_pdev = {$' "$core" &&
  grep -q '^static int __init vimc_init(void)$' "$core" || {
  echo "build-modules: vimc-core.c has changed: its platform device or init was not found" >&2
  exit 1
}
sed -i -e '/^static struct platform_device vimc_pdev = {$/,/^};$/d' \
  -e '/^static int __init vimc_init(void)$/,$d' "$core"
cat "$(dirname "$0")/vimc-instances.c" >>"$core"
printf 'obj-m := vimc.o\nvimc-y := %s\n' \
  "$(cd "$work/vimc" && ls ./*.c | sed 's|^\./||; s|\.c$|.o|' | paste -sd' ')" >"$work/vimc/Kbuild"

for module in gpio-sim vimc; do
  nice make "${make_args[@]}" M="$work/$module" modules >"$work/$module.log" 2>&1 || {
    cat "$work/$module.log" >&2
    exit 1
  }
done
mkdir -p "$out.partial"
cp "$work/gpio-sim/gpio-sim.ko" "$work/vimc/vimc.ko" "$out.partial/"
touch "$out.partial/$stamp"
rm -rf "$out"
mv "$out.partial" "$out"
echo "build-modules: $out ready ($(modinfo -F vermagic "$out/gpio-sim.ko"))"
