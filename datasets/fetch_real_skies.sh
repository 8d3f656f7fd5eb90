#!/usr/bin/env bash
# Real photographed HDR skies (Poly Haven, CC0) as reference frames in the project's
# lat-long convention, fetched reproducibly from distribution packages:
#
#   datasets/cache/  downloaded packages and the EXRs extracted from them (gitignored)
#   datasets/real/   the converted frames, written by `build/skycal import` (gitignored)
#
# Every download and every extracted file is checked against a SHA-256 pinned below; a
# mismatch is an error (exit 1). Re-running skips what is already there and verified.
# See datasets/README.md for what each frame is and its known defects.
#
# usage: datasets/fetch_real_skies.sh [--with-npm] [--force]
#   --with-npm   also fetch npm @pmndrs/assets (sky: partly cloudy, sun ~48 deg; dawn)
#   --force      re-extract and re-import even when the outputs are up to date
# Environment: SKYCAL (default build/skycal) is the binary used for `skycal import`.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
CACHE="$ROOT/datasets/cache"
REAL="$ROOT/datasets/real"
SKYCAL="${SKYCAL:-$ROOT/build/skycal}"

# --- pinned sources ----------------------------------------------------------------------
DEB_PACKAGE="blender-data"
DEB_VERSION="3.4.1+dfsg-2"                       # Debian 12 (bookworm) main
DEB_FILE="blender-data_3.4.1+dfsg-2_all.deb"     # 31,389,128 bytes
DEB_SHA256="5ceaf56a49ba3ded95c751d739aeec3d19e7fad76fba5cb70666986af9303b0e"
DEB_WORLD_DIR="usr/share/blender/datafiles/studiolights/world"
# Extracted world EXRs (1024x512 float, DWAB) and their SHA-256.
declare -A DEB_EXR_SHA256=(
  [sunrise]="b97206217e29763d62d9a65ad2d7058460acfb4824659e7a59f5bde374f21937"
  [sunset]="a164f20b86bc43ba4afd66c988a20a9dd5f1a0a5d8e960aed57a33f78119c168"
  [city]="70940108df90c0721799d29f758ca79e67e509d9a2636487e639db7779561524"
  [forest]="63ad3243d0f9c29bd1f51b9a3bbf5c0ad25ea39299698dba6cfc29d1660d6008"
  [night]="a46488f5cb744f325abc9f5af3c3eeb5d9393df69b5178fbe727538522120045"
)
# The frames to import from it, and the sun option of each (skies with a visible sun).
DEB_FRAMES=(sunrise sunset city forest night)
declare -A DEB_SUN=([sunrise]="--detect-sun" [sunset]="--detect-sun" [city]="" [forest]="" [night]="")

NPM_PACKAGE="@pmndrs/assets"
NPM_VERSION="1.7.0"
NPM_FILE="pmndrs-assets-1.7.0.tgz"               # 13,774,995 bytes (the registry tarball)
NPM_SHA256="152bd218a3390703f184f0c6ce16e73c8f0a87f32d38530d418a09d33d8208dc"
# Decoded from hdri/<name>.exr.js (base64 data URL): 512x256 half, DWAB.
declare -A NPM_EXR_SHA256=(
  [sky]="a72412700b91a49080a582420476d2ab9a1e8fd181031f4ae7ec5e2596addc2a"
  [dawn]="02529d0a04dbc6e761adb9b4f6bcb07b0ef3931b218b394ee6be68b1fe39ce79"
)
NPM_FRAMES=(sky dawn)
# dawn: the sun is hidden behind the ridge (twilight); the brightest spot is the glow above
# it, 5 deg up, so no sun direction is recorded (see datasets/README.md).
declare -A NPM_SUN=([sky]="--detect-sun" [dawn]="")

# --- options -----------------------------------------------------------------------------
WITH_NPM=0
FORCE=0
for arg in "$@"; do
  case "$arg" in
    --with-npm) WITH_NPM=1 ;;
    --force) FORCE=1 ;;
    -h|--help) sed -n '2,16p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "fetch_real_skies.sh: unknown option '$arg' (expected --with-npm, --force, --help)" >&2; exit 2 ;;
  esac
done

log() { echo "[fetch_real_skies] $*" >&2; }
die() { echo "fetch_real_skies.sh: error: $*" >&2; exit 1; }
sha256() { sha256sum "$1" | cut -d' ' -f1; }
# verified FILE SHA: true when FILE exists and has that SHA-256.
verified() { [[ -f "$1" ]] && [[ "$(sha256 "$1")" == "$2" ]]; }
human_size() { numfmt --to=iec --suffix=B "$(stat -c %s "$1")" 2>/dev/null || stat -c %s "$1"; }

START_NS=$(date +%s%N)
DOWNLOADED=0
mkdir -p "$CACHE" "$REAL"

[[ -x "$SKYCAL" ]] || die "$SKYCAL not found: build first (cmake -S . -B build -G Ninja && ninja -C build) or set SKYCAL"
"$SKYCAL" import --help >/dev/null 2>&1 || die "$SKYCAL has no 'import' verb: rebuild (ninja -C build)"
SKYCAL_VERSION="$("$SKYCAL" --version)"

# fetch_checked FILE SHA FETCH_COMMAND...: FILE (under $CACHE) verified, downloading if needed.
fetch_checked() {
  local file="$1" want="$2"
  shift 2
  local path="$CACHE/$file"
  if verified "$path" "$want"; then
    log "$file: present, SHA-256 verified"
    return 0
  fi
  [[ -f "$path" ]] && { log "$file: present but its SHA-256 differs from the pinned one; downloading again"; rm -f "$path"; }
  log "$file: downloading"
  "$@"
  [[ -f "$path" ]] || die "$file: the download produced no file"
  DOWNLOADED=$((DOWNLOADED + $(stat -c %s "$path")))
  local got
  got="$(sha256 "$path")"
  if [[ "$got" != "$want" ]]; then
    mv -f "$path" "$path.mismatch"
    die "$file: SHA-256 mismatch: got $got, pinned $want (kept as $path.mismatch). The archive" \
        "changed upstream; check it and update the pin in $0 on purpose."
  fi
  log "$file: $(human_size "$path"), SHA-256 verified"
}

apt_download() {
  # apt-get download runs in the current directory. Without package lists (fresh image)
  # the pinned version is unknown: refresh them once and retry.
  (cd "$CACHE" && apt-get download "$DEB_PACKAGE=$DEB_VERSION") && return 0
  log "apt-get download failed; running apt-get update and retrying"
  if [[ $(id -u) -ne 0 ]]; then
    die "apt-get download $DEB_PACKAGE=$DEB_VERSION failed and apt-get update needs root (run: sudo apt-get update)"
  fi
  apt-get update -qq || die "apt-get update failed"
  (cd "$CACHE" && apt-get download "$DEB_PACKAGE=$DEB_VERSION") ||
    die "apt-get download $DEB_PACKAGE=$DEB_VERSION failed (is Debian 12 main in the APT sources?)"
}

npm_download() {
  command -v npm >/dev/null || die "npm not found (apt-get install npm) and --with-npm was given"
  npm pack "$NPM_PACKAGE@$NPM_VERSION" --pack-destination "$CACHE" --silent >/dev/null ||
    die "npm pack $NPM_PACKAGE@$NPM_VERSION failed"
}

# import_frame NAME SOURCE SOURCE_SHA SUN_OPTION: datasets/real/NAME.exr, unless its stamp
# says it was made from this source, with these options and this skycal, and it is intact.
import_frame() {
  local name="$1" src="$2" src_sha="$3" sun_opt="$4"
  local out="$REAL/$name.exr" stamp="$REAL/.$name.stamp"
  local args="--source-convention blender $sun_opt"
  local key="source=$src_sha args=$args tool=$SKYCAL_VERSION"
  if [[ $FORCE -eq 0 && -f "$out" && -f "$stamp" ]] && [[ "$(head -n1 "$stamp")" == "$key" ]] &&
     [[ "$(sed -n 2p "$stamp")" == "$(sha256 "$out")" ]]; then
    log "real/$name.exr: up to date"
    return 0
  fi
  log "real/$name.exr: importing $(basename "$src") ($args)"
  # shellcheck disable=SC2086  # $args is a list of options
  "$SKYCAL" import --in "$src" --out "$out" $args --json >"$REAL/.$name.import.json" ||
    die "skycal import failed for $src (see the message above)"
  printf '%s\n%s\n' "$key" "$(sha256 "$out")" >"$stamp"
}

# --- Debian blender-data -----------------------------------------------------------------
fetch_checked "$DEB_FILE" "$DEB_SHA256" apt_download
DEB_OUT="$CACHE/blender-data"
mkdir -p "$DEB_OUT"
need_extract=$FORCE
for name in "${DEB_FRAMES[@]}"; do
  verified "$DEB_OUT/$name.exr" "${DEB_EXR_SHA256[$name]}" || need_extract=1
done
if [[ $need_extract -eq 1 ]]; then
  log "extracting $DEB_WORLD_DIR/*.exr from $DEB_FILE"
  tmp="$(mktemp -d "$CACHE/.extract.XXXXXX")"
  trap 'rm -rf "$tmp"' EXIT
  # dpkg-deb -x cannot filter; --fsys-tarfile gives the same data.tar for tar to filter.
  dpkg-deb --fsys-tarfile "$CACHE/$DEB_FILE" |
    tar -x -C "$tmp" --wildcards "./$DEB_WORLD_DIR/*.exr" "./$DEB_WORLD_DIR/license.txt"
  for name in "${DEB_FRAMES[@]}"; do
    f="$tmp/$DEB_WORLD_DIR/$name.exr"
    verified "$f" "${DEB_EXR_SHA256[$name]}" || die "$DEB_FILE: $DEB_WORLD_DIR/$name.exr is missing or its SHA-256 is not the pinned one"
    mv -f "$f" "$DEB_OUT/$name.exr"
  done
  mv -f "$tmp/$DEB_WORLD_DIR/license.txt" "$DEB_OUT/license.txt"
  rm -rf "$tmp"
  trap - EXIT
else
  log "blender-data: extracted EXRs present, SHA-256 verified"
fi
for name in "${DEB_FRAMES[@]}"; do
  import_frame "$name" "$DEB_OUT/$name.exr" "${DEB_EXR_SHA256[$name]}" "${DEB_SUN[$name]}"
done

# --- npm @pmndrs/assets (optional) -------------------------------------------------------
if [[ $WITH_NPM -eq 1 ]]; then
  fetch_checked "$NPM_FILE" "$NPM_SHA256" npm_download
  NPM_OUT="$CACHE/pmndrs-assets"
  mkdir -p "$NPM_OUT"
  for name in "${NPM_FRAMES[@]}"; do
    exr="$NPM_OUT/$name.exr"
    if [[ $FORCE -eq 1 ]] || ! verified "$exr" "${NPM_EXR_SHA256[$name]}"; then
      log "decoding package/hdri/$name.exr.js (base64 data URL) from $NPM_FILE"
      # The module is one line: export default 'data:application/exr;base64,<data>'
      tar -xzOf "$CACHE/$NPM_FILE" "package/hdri/$name.exr.js" |
        sed -e "s/^export default '[^,]*,//" -e "s/'[;[:space:]]*\$//" | base64 -d >"$exr.tmp" ||
        die "$NPM_FILE: could not decode package/hdri/$name.exr.js"
      verified "$exr.tmp" "${NPM_EXR_SHA256[$name]}" ||
        die "$NPM_FILE: hdri/$name.exr.js decodes to an EXR whose SHA-256 is not the pinned one"
      mv -f "$exr.tmp" "$exr"
    fi
    import_frame "$name" "$exr" "${NPM_EXR_SHA256[$name]}" "${NPM_SUN[$name]}"
  done
fi

ELAPSED_MS=$((($(date +%s%N) - START_NS) / 1000000))
log "done in $((ELAPSED_MS / 1000)).$(printf %03d $((ELAPSED_MS % 1000))) s (downloaded $DOWNLOADED bytes); frames in datasets/real/:"
for f in "$REAL"/*.exr; do
  log "  $(basename "$f")  $(human_size "$f")"
done
