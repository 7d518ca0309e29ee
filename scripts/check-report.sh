#!/usr/bin/env bash
# Opens a report in a real browser (headless Chromium) and checks what a reader would see: every
# <img> on the page loaded (complete, naturalWidth > 0) and the tables are there.
#
#   scripts/check-report.sh DIR      DIR = a run folder (DIR/report/index.html), a report folder,
#                                    or the index.html itself
#
# Installs Debian `chromium` when missing (as root). Exit 0 with "PASSED", 1 with "FAILED: why",
# or 0 with "SKIPPED: why" only when no Chromium can be had on this machine.
# TABLES="runs rows notok" lists the table ids that must exist (default: runs rows notok);
# MIN_IMAGES (default 1) the fewest images the page must hold.
set -uo pipefail
say() { echo "check-report: $*"; }
[ $# -eq 1 ] || { sed -n '2,12p' "$0" | sed 's/^# \{0,1\}//'; exit 2; }
arg=$1
if [ -f "$arg" ]; then page=$arg
elif [ -f "$arg/report/index.html" ]; then page=$arg/report/index.html
elif [ -f "$arg/index.html" ]; then page=$arg/index.html
else say "FAILED: no index.html in $arg or $arg/report"; exit 1; fi
page=$(cd "$(dirname "$page")" && pwd)/$(basename "$page")

browser=
for b in chromium chromium-browser google-chrome; do
    command -v "$b" >/dev/null && { browser=$b; break; }
done
if [ -z "$browser" ]; then
    if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
        say "installing chromium (Debian package)"
        export DEBIAN_FRONTEND=noninteractive
        timeout 600 apt-get install -y -q chromium >/tmp/mfx-chromium-apt.log 2>&1 ||
            { timeout 300 apt-get update -q >>/tmp/mfx-chromium-apt.log 2>&1 &&
              timeout 600 apt-get install -y -q chromium >>/tmp/mfx-chromium-apt.log 2>&1; }
        command -v chromium >/dev/null && browser=chromium
    fi
    [ -n "$browser" ] || { say "SKIPPED: no Chromium here and it cannot be installed (not root, no apt, or apt failed: /tmp/mfx-chromium-apt.log)"; exit 0; }
fi

# A copy of the report folder (the original is left untouched; relative image paths still
# resolve) whose page gets a script that, once everything has loaded, writes what it found into
# the DOM that --dump-dom prints.
work=$(mktemp -d /tmp/mfx-chromium.XXXXXX)
trap 'rm -rf "$work"' EXIT
profile=$work/profile
mkdir -p "$profile" "$work/report"
cp -r "$(dirname "$page")"/. "$work/report/"
probe=$work/report/.check-report.html
{
    cat "$page"
    cat <<'JS'
<script>
window.addEventListener("load", function () {
  var imgs = Array.prototype.slice.call(document.images);
  var bad = imgs.filter(function (i) { return !(i.complete && i.naturalWidth > 0); })
                .map(function (i) { return i.getAttribute("src"); });
  var ids = Array.prototype.slice.call(document.querySelectorAll("table"))
                .map(function (t) { return t.id || "(no id)"; });
  var pre = document.createElement("pre");
  pre.id = "mfx-check";
  pre.textContent = "MFXCHECK images=" + imgs.length + " bad=" + JSON.stringify(bad) +
                    " tables=" + JSON.stringify(ids) + " END";
  document.body.appendChild(pre);
});
</script>
JS
} >"$probe"

dom=$(timeout 90 "$browser" --headless --no-sandbox --disable-gpu --disable-background-networking \
    --disable-component-update --disable-sync --no-first-run --user-data-dir="$profile" \
    --allow-file-access-from-files --virtual-time-budget=15000 --dump-dom "file://$probe" 2>"$profile/stderr.log")
rc=$?
line=$(printf '%s' "$dom" | grep -o 'MFXCHECK .* END' | head -n 1)
if [ -z "$line" ]; then
    say "FAILED: $browser (exit $rc) gave no check result for $page"
    tail -n 15 "$profile/stderr.log"
    exit 1
fi
n=$(sed 's/.*images=\([0-9]*\).*/\1/' <<<"$line")
bad=$(sed 's/.* bad=\(\[[^]]*\]\).*/\1/' <<<"$line")
tables=$(sed 's/.* tables=\(\[[^]]*\]\).*/\1/' <<<"$line")
status=0
if [ "$bad" != "[]" ]; then say "FAILED: images that did not load: $bad"; status=1; fi
if [ "$n" -lt "${MIN_IMAGES:-1}" ]; then say "FAILED: $n images on the page (want at least ${MIN_IMAGES:-1})"; status=1; fi
for t in ${TABLES:-runs rows notok}; do
    grep -q "\"$t\"" <<<"$tables" || { say "FAILED: no table id=\"$t\" (tables: $tables)"; status=1; }
done
if [ "$status" = 0 ]; then
    say "PASSED: $page in $($browser --version 2>/dev/null | head -n 1): $n images loaded, tables $tables"
fi
exit "$status"
