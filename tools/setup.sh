#!/usr/bin/env bash
# Install spectracam on a fresh Debian/Ubuntu machine, into the project's virtual environment .venv/
# (so it also works where pip refuses to touch the system Python, PEP 668):
#   bash tools/setup.sh          # the package, its runtime dependencies and the "exr" extra
#   bash tools/setup.sh --test   # ... plus the test dependencies (the "test" extra, which holds "docs")
#   bash tools/setup.sh --docs   # ... plus what builds the documentation site (the "docs" extra; mkdocs.yml)
# Then run .venv/bin/python -m spectracam ... (or `source .venv/bin/activate`).
# .venv is made by `python3 -m venv` with the python3 first on PATH (Python >= 3.11); on Debian and
# Ubuntu that needs the python3-venv package, installed here when missing and we may.
# libLLVM 19 (Debian package libllvm19) is what Mitsuba's LLVM backend needs; without it
# spectracam still works, on the much slower scalar variant.
# Running it again is quick: pip runs only when pyproject.toml, the extras or the checkout's
# path changed since the last successful run (the stamp .venv/.spectracam-setup). rm -rf .venv
# to start over.
set -euo pipefail
cd "$(dirname "$0")/.."
extras="exr"
case "${1:-}" in
  "") ;;
  --test) extras="exr,test" ;;
  --docs) extras="exr,docs" ;;
  *) echo "usage: bash tools/setup.sh [--test | --docs]" >&2; exit 2 ;;
esac

# May we install Debian packages? (root, or passwordless sudo, and apt-get)
SUDO=""
can_apt() {
  command -v apt-get >/dev/null 2>&1 || return 1
  [ "$(id -u)" = 0 ] && return 0
  if command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then SUDO="sudo -n"; return 0; fi
  return 1
}
apt_updated=""
apt_update() {
  [ -n "$apt_updated" ] && return 0
  $SUDO env DEBIAN_FRONTEND=noninteractive apt-get update -qq
  apt_updated=1
}
apt_install() {
  apt_update
  $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "$@" >/dev/null
}

have_llvm19() {  # (a non-root user's PATH may lack /sbin)
  # grep reads everything (no -q): with pipefail, ldconfig killed by SIGPIPE would count as not found
  { ldconfig -p 2>/dev/null || /sbin/ldconfig -p 2>/dev/null; } | grep -E 'libLLVM(-19\.so|\.so\.19)' >/dev/null
}
if ! have_llvm19; then
  if ! command -v apt-get >/dev/null 2>&1; then
    echo "setup: warning: no apt-get; install libLLVM 19 yourself and set DRJIT_LIBLLVM_PATH, or" \
         "spectracam falls back to the slow scalar_spectral variant" >&2
  elif can_apt; then
    echo "setup: installing libllvm19 (Mitsuba's LLVM backend needs it)"
    apt_install libllvm19
  else
    echo "setup: warning: libLLVM 19 is missing and this user cannot install it (apt-get install libllvm19);" \
         "spectracam will fall back to the slow scalar_spectral variant" >&2
  fi
fi

# --test: Debian's Chromium and its ChromeDriver for the page's browser test (tests/test_view.py), which
# is skipped with its reason where they cannot be installed; nothing downloads a browser.
if [ "$extras" = "exr,test" ] && { [ ! -x /usr/bin/chromium ] || [ ! -x /usr/bin/chromedriver ]; }; then
  if can_apt; then
    echo "setup: installing chromium and chromium-driver (the browser test of spectracam view)"
    apt_install chromium chromium-driver
  else
    echo "setup: warning: chromium/chromium-driver missing and this user cannot install them" \
         "(apt-get install chromium chromium-driver); the browser test will be skipped" >&2
  fi
fi

# --test: the real cameras' measurements the off-axis tests read (issue 37): lensfun's lens database and libcamera's
# tuning files (the Raspberry Pi HQ camera's lens-shading tables); those tests are skipped with their reason where
# the packages cannot be installed.
if [ "$extras" = "exr,test" ] && { [ ! -d /usr/share/lensfun/version_1 ] || [ ! -d /usr/share/libcamera/ipa ]; }; then
  if can_apt; then
    echo "setup: installing liblensfun-data-v1 and libcamera-ipa (measured lenses and lens-shading tables)"
    apt_install liblensfun-data-v1 libcamera-ipa || echo "setup: warning: liblensfun-data-v1/libcamera-ipa could" \
      "not be installed; the tests that read them will be skipped" >&2
  else
    echo "setup: warning: liblensfun-data-v1/libcamera-ipa missing and this user cannot install them; the tests" \
         "that read them will be skipped" >&2
  fi
fi

# The virtual environment: kept when its python runs and has pip, made anew otherwise.
PY=.venv/bin/python
venv_ok() {
  [ -x "$PY" ] && "$PY" -c 'import sys; sys.exit(sys.version_info < (3, 11))' 2>/dev/null \
    && "$PY" -m pip --version >/dev/null 2>&1
}
if ! venv_ok; then
  if ! command -v python3 >/dev/null 2>&1; then
    echo "setup: error: no python3 on PATH; install Python >= 3.11 (Debian/Ubuntu: apt-get install python3 python3-venv)" >&2
    exit 1
  fi
  pyver=$(python3 -c 'import sys; print("%d.%d" % sys.version_info[:2])')
  if ! python3 -c 'import sys; sys.exit(sys.version_info < (3, 11))'; then
    echo "setup: error: spectracam needs Python >= 3.11, but python3 ($(command -v python3)) is $pyver" >&2
    exit 1
  fi
  rm -rf .venv
  echo "setup: making the virtual environment .venv (python3 $pyver)"
  err=""
  if ! err=$(python3 -m venv .venv 2>&1) || ! venv_ok; then
    # Debian and Ubuntu keep venv's ensurepip in python3-venv (python3.X-venv), not in python3.
    rm -rf .venv
    if can_apt; then
      echo "setup: installing python3-venv (python3 -m venv needs it)"
      apt_update
      # the default python3's venv, and that of the python3 on PATH where apt knows it
      pkgs="python3-venv"
      if apt-cache show "python$pyver-venv" >/dev/null 2>&1; then pkgs="$pkgs python$pyver-venv"; fi
      apt_install $pkgs
      err=$(python3 -m venv .venv 2>&1) || true
    fi
    if ! venv_ok; then
      rm -rf .venv
      echo "setup: error: 'python3 -m venv .venv' failed: $(command -v python3) has no venv/ensurepip;" \
           "install python$pyver-venv (Debian/Ubuntu: sudo apt-get install python3-venv) and run again" \
           "(python3 said: $(printf '%s' "$err" | tr -s '\n' ' ' | cut -c1-240))" >&2
      exit 1
    fi
  fi
fi

# --test: real cameras' own measurements for `spectracam validate` (tests/test_validate_wb.py): darktable's
# wb_presets.json and rawtherapee-data's DCP profiles.  Only these data files are taken: `apt-get download` and
# `dpkg-deb -x` of the two packages into .venv/share/spectracam/debian (darktable itself would pull in ~100
# libraries; the two .deb are 21 MB and this step takes a few seconds).  Skipped with the reason where apt-get
# cannot fetch them; the tests then skip.  The system's /usr/share copies are used when installed.
debian_data() {
  local dest=.venv/share/spectracam/debian wb=share/darktable/wb_presets.json dcp=share/rawtherapee/dcpprofiles
  local pkgs="" p tmp member
  [ -f "/usr/$wb" ] || [ -f "$dest/usr/$wb" ] || pkgs="$pkgs darktable"
  [ -d "/usr/$dcp" ] || [ -d "$dest/usr/$dcp" ] || pkgs="$pkgs rawtherapee-data"
  [ -n "$pkgs" ] || return 0
  local skip="the white-balance-preset and DCP checks of spectracam validate will be skipped (they need Debian's$pkgs)"
  if ! command -v apt-get >/dev/null 2>&1 || ! command -v dpkg-deb >/dev/null 2>&1; then
    echo "setup: warning: no apt-get/dpkg-deb: $skip" >&2
    return 0
  fi
  if ! can_apt; then
    echo "setup: warning: this user may not run apt-get (apt-get download$pkgs): $skip" >&2
    return 0
  fi
  echo "setup: fetching the data files of$pkgs (spectracam validate's real-camera checks)"
  tmp=$(mktemp -d)
  # (as root, apt warns that it downloads unsandboxed into a directory _apt cannot write: harmless, kept quiet)
  # shellcheck disable=SC2086
  if ! (cd "$tmp" && $SUDO apt-get download -qq $pkgs) >/dev/null 2>"$tmp/err"; then
    apt_update
    # shellcheck disable=SC2086
    if ! (cd "$tmp" && $SUDO apt-get download -qq $pkgs) >/dev/null 2>"$tmp/err"; then
      echo "setup: warning: apt-get download$pkgs failed ($(grep -v '^W:' "$tmp/err" | tr -s '\n' ' ' | cut -c1-200)): $skip" >&2
      $SUDO rm -rf "$tmp"
      return 0
    fi
  fi
  mkdir -p "$dest"
  for p in "$tmp"/*.deb; do
    case "$p" in
      */darktable_*) member="./usr/$wb" ;;
      */rawtherapee-data_*) member="./usr/$dcp" ;;
      *) continue ;;
    esac
    dpkg-deb --fsys-tarfile "$p" | tar -x -C "$dest" "$member" \
      || echo "setup: warning: $(basename "$p") has no $member: $skip" >&2
  done
  $SUDO rm -rf "$tmp"
}
if [ "$extras" = "exr,test" ]; then
  debian_data
fi

stamp=.venv/.spectracam-setup
want="$(pwd) $(sha256sum pyproject.toml | cut -c1-64)"
have=$(cat "$stamp" 2>/dev/null || true)
if [ "$have" = "$want $extras" ] || [ "$have" = "$want exr,test" ]; then
  echo "setup: done (.venv is up to date)"
  exit 0
fi
rm -f "$stamp"
echo "setup: installing spectracam[$extras] into .venv"
"$PY" -m pip install --disable-pip-version-check --progress-bar off -e ".[$extras]"
echo "$want $extras" > "$stamp"
echo "setup: done"
