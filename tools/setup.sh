#!/usr/bin/env bash
# Install everything spectracam needs on a fresh Debian/Ubuntu machine.
#   bash tools/setup.sh          # the package and its runtime dependencies
#   bash tools/setup.sh --test   # ... plus the test dependencies
# libLLVM 19 (Debian package libllvm19) is what Mitsuba's LLVM backend needs; without it
# spectracam still works, on the much slower scalar variant.
set -euo pipefail
cd "$(dirname "$0")/.."
extras=""
[ "${1:-}" = "--test" ] && extras="[test]"

have_llvm19() { ldconfig -p 2>/dev/null | grep -qE 'libLLVM(-19\.so|\.so\.19)'; }
if ! have_llvm19; then
  if command -v apt-get >/dev/null 2>&1; then
    SUDO=""
    if [ "$(id -u)" != 0 ]; then
      if command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then SUDO="sudo -n"; fi
    fi
    if [ "$(id -u)" = 0 ] || [ -n "$SUDO" ]; then
      echo "setup: installing libllvm19 (Mitsuba's LLVM backend needs it)"
      $SUDO env DEBIAN_FRONTEND=noninteractive apt-get update -qq
      $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq libllvm19 >/dev/null
    else
      echo "setup: warning: libLLVM 19 is missing and this user cannot install it (apt-get install libllvm19);" \
           "spectracam will fall back to the slow scalar_spectral variant" >&2
    fi
  else
    echo "setup: warning: no apt-get; install libLLVM 19 yourself and set DRJIT_LIBLLVM_PATH, or" \
         "spectracam falls back to the slow scalar_spectral variant" >&2
  fi
fi
python3 -m pip install --disable-pip-version-check -q -e ".${extras}"
echo "setup: done"
