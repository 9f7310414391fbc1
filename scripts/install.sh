#!/usr/bin/env bash
# Installs NIFT cell into ./.venv: the Debian libraries Open3D needs, then the package itself.
# Usage: scripts/install.sh [--test]      (--test adds pytest, Selenium and Debian's Chromium for the
#                                          teach page's browser test; NIFT_UNPINNED=1 skips scripts/constraints.txt)
set -euo pipefail
cd "$(dirname "$0")/.."

need_apt=()
debian=(libusb-1.0-0 libgl1 libgomp1)
[ "${1:-}" = "--test" ] && debian+=(chromium chromium-driver)  # a real browser, from Debian (no download at run time)
for pkg in "${debian[@]}"; do
    dpkg -s "$pkg" >/dev/null 2>&1 || need_apt+=("$pkg")
done
if [ ${#need_apt[@]} -gt 0 ]; then
    sudo_cmd=""; [ "$(id -u)" -ne 0 ] && sudo_cmd="sudo"
    echo "installing Debian packages: ${need_apt[*]}"
    $sudo_cmd apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq "${need_apt[@]}" >/dev/null
fi

pip_install() {  # quiet pip; drop the machine's notes about absent local mirrors
    .venv/bin/python -m pip install -q "$@" 2> >(grep -v "is ignored: it is neither" >&2)
}
[ -x .venv/bin/python ] || python3 -m venv .venv
pip_install --upgrade pip
# torch first and exactly pinned, so nothing later can pull a CUDA build.
pip_install "torch==2.13.0"
extra=""; [ "${1:-}" = "--test" ] && extra="[test]"
# The versions the README's figures were measured with: a newer PyBullet or CoACD changes physics.
pins=(-c scripts/constraints.txt); [ "${NIFT_UNPINNED:-0}" = "1" ] && pins=()
pip_install -e ".${extra}" "${pins[@]}"
echo "NIFT cell installed in .venv ($(.venv/bin/nift --version))"
