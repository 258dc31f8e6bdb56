#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Sourced by the setup scripts. apt_install_missing PACKAGE... installs with apt those of the
# packages that are not installed yet, so a second run costs only the dpkg queries. A package
# named PACKAGE:ARCH adds ARCH as a foreign architecture first (once). Needs root or sudo when
# anything is missing.
apt_install_missing() {
  local missing=() package
  for package in "$@"; do
    dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed" || missing+=("$package")
  done
  [ ${#missing[@]} -gt 0 ] || return 0
  local sudo=""
  [ "$(id -u)" -ne 0 ] && sudo="sudo"
  export DEBIAN_FRONTEND=noninteractive
  local arch
  for arch in $(printf '%s\n' "${missing[@]}" | sed -n 's/^[^:]*://p' | sort -u); do
    dpkg --print-foreign-architectures | grep -qx "$arch" || $sudo dpkg --add-architecture "$arch"
  done
  $sudo apt-get update -qq
  $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
}
