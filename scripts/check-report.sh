#!/usr/bin/env bash
# Opens a report in a real browser (headless Chromium) and checks what a reader would see: every
# <img> on the page loaded (complete, naturalWidth > 0), the tables are there, and every chart's
# layout record (<stem>.layout.json beside its SVG) passes the reader's rules of
# report/src/charts/layout.rs `check`: the legend box does not overlap the plot area; each
# numeric axis contains its data and reaches at most a decade beyond it (log: ≤ 10× padding on
# each side; linear: axis span ≤ 10 × max(data span, a tenth of the data's magnitude)), or data
# outside the axis has an off-scale mark (`off_scale` > 0); no tick label repeats (category names
# included); no text drawn on the chart (floor and front names) overlaps another or a marker; no
# two markers of different series sit within 3 px of each other (one hiding the other); no two
# series share a colour and a marker.
#
#   scripts/check-report.sh DIR      DIR = a run folder (DIR/report/index.html), a report folder,
#                                    or the index.html itself
#
# Installs Debian `chromium` when missing (as root). Exit 0 with "PASSED", 1 with "FAILED: why",
# or 0 with "SKIPPED: why" only when no Chromium can be had on this machine.
# TABLES="runs rows notok" lists the table ids that must exist (default: runs rows notok);
# MIN_CHARTS (default 0) the fewest charts with a layout record;
# MIN_IMAGES (default 1) the fewest images the page must hold.
# The run for a paper (report/src/latex.rs), checked when the report folder has latex/ or
# LATEX=1 requires it: numbers.tex defines macros, the booktabs tables and sample.tex exist,
# every SVG chart has its PDF with a font embedded, and sample.tex (which \inputs them all and
# includes a chart PDF) compiles with pdflatex. Without pdflatex that part says SKIPPED, except
# in CI (CI=true), where it FAILS (scripts/setup.sh installs texlive-latex-base and -recommended).
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
        # The install's log is kept only when no Chromium comes of it (the skip names it): a
        # fixed /tmp/mfx-* file would outlive the run and fail CI's clean-temp check.
        aptlog=$(mktemp -t chromium-apt.XXXXXX.log)
        timeout 600 apt-get install -y -q chromium >"$aptlog" 2>&1 ||
            { timeout 300 apt-get update -q >>"$aptlog" 2>&1 &&
              timeout 600 apt-get install -y -q chromium >>"$aptlog" 2>&1; }
        command -v chromium >/dev/null && browser=chromium && rm -f "$aptlog"
    fi
    [ -n "$browser" ] || { say "SKIPPED: no Chromium here and it cannot be installed (not root, no apt, or apt failed: ${aptlog:-no install tried})"; exit 0; }
fi

# A copy of the report folder (the original is left untouched; relative image paths still
# resolve) whose page gets a script that, once everything has loaded, writes what it found into
# the DOM that --dump-dom prints.
work=$(mktemp -d /tmp/mfx-chromium.XXXXXX)
trap 'rm -rf "$work"' EXIT
profile=$work/profile
mkdir -p "$profile" "$work/report"
cp -r "$(dirname "$page")"/. "$work/report/"
# The FLIP images live in the run folder (run/flip/), referenced as ../flip/… from the page.
[ -d "$(dirname "$page")/../flip" ] && cp -r "$(dirname "$page")/../flip" "$work/flip"
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
  // Every chart's layout record, read as the page sees it, judged by layout.rs's rules.
  var charts = 0, layout = [];
  imgs.forEach(function (i) {
    var src = i.getAttribute("src");
    if (!/\.svg$/.test(src)) return;
    var rec = src.replace(/\.svg$/, ".layout.json"), l = null;
    try {
      var x = new XMLHttpRequest();
      x.open("GET", rec, false);
      x.send(null);
      l = JSON.parse(x.responseText);
    } catch (e) { layout.push(rec + ": no layout record (" + e + ")"); return; }
    charts++;
    var p = l.plot, g = l.legend;
    if (g && g.x < p.x + p.w && p.x < g.x + g.w && g.y < p.y + p.h && p.y < g.y + g.h)
      layout.push(l.stem + ": legend overlaps the plot area");
    ["x", "y"].forEach(function (n) {
      var a = l[n];
      a.ticks.forEach(function (t, k) {
        if (a.ticks.indexOf(t) < k) layout.push(l.stem + ": " + n + " tick label '" + t + "' repeats");
      });
      if (a.categorical || !a.data) return;
      var r0 = a.range[0], r1 = a.range[1], d0 = a.data[0], d1 = a.data[1];
      var tol = Math.abs(r1 - r0) * 1e-9;
      if ((d0 < r0 - tol || d1 > r1 + tol) && !a.off_scale)
        layout.push(l.stem + ": " + n + " data outside the axis with no off-scale mark");
      if (a.off_scale) return;
      if (a.log) {
        if (d0 <= 0 || r0 <= 0 || d0 / r0 > 10 * (1 + 1e-9) || r1 / d1 > 10 * (1 + 1e-9))
          layout.push(l.stem + ": " + n + " log axis " + r0 + ".." + r1 + " reaches more than a decade beyond its data " + d0 + ".." + d1);
      } else {
        var span = Math.max(d1 - d0, 0.1 * Math.max(Math.abs(d0), Math.abs(d1)));
        if (span > 0 && (r1 - r0) > 10 * span * (1 + 1e-9))
          layout.push(l.stem + ": " + n + " axis " + r0 + ".." + r1 + " is more than ten times its data's span " + d0 + ".." + d1);
      }
    });
    var hit = function (a, b) {
      return a.x < b.x + b.w && b.x < a.x + a.w && a.y < b.y + b.h && b.y < a.y + a.h;
    };
    var labels = l.labels || [], marks = l.marks || [], styles = l.styles || [];
    labels.forEach(function (t, k) {
      labels.slice(0, k).forEach(function (o) {
        if (hit(t.rect, o.rect)) layout.push(l.stem + ": label '" + t.text + "' overlaps label '" + o.text + "'");
      });
      if (marks.some(function (m) { return hit(m.rect, t.rect); }))
        layout.push(l.stem + ": label '" + t.text + "' covers a marker");
    });
    var hidden = marks.some(function (m, k) {
      return marks.slice(0, k).some(function (o) {
        return o.series !== m.series &&
          Math.hypot(m.rect.x + m.rect.w / 2 - o.rect.x - o.rect.w / 2,
                     m.rect.y + m.rect.h / 2 - o.rect.y - o.rect.h / 2) < 3;
      });
    });
    if (hidden) layout.push(l.stem + ": markers of two series sit on the same spot");
    styles.forEach(function (st, k) {
      if (st && styles.indexOf(st) < k) layout.push(l.stem + ": series " + k + " looks like an earlier one (" + st + ")");
    });
  });
  var pre = document.createElement("pre");
  pre.id = "mfx-check";
  pre.textContent = "MFXCHECK images=" + imgs.length + " bad=" + JSON.stringify(bad) +
                    " tables=" + JSON.stringify(ids) + " charts=" + charts +
                    " layout=" + JSON.stringify(layout) + " END";
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
charts=$(sed 's/.* charts=\([0-9]*\).*/\1/' <<<"$line")
layout=$(sed 's/.* layout=\(\[.*\]\) END$/\1/' <<<"$line")
status=0
if [ "$layout" != "[]" ]; then say "FAILED: chart layout: $layout"; status=1; fi
if [ "$charts" -lt "${MIN_CHARTS:-0}" ]; then say "FAILED: $charts charts with a layout record (want at least ${MIN_CHARTS:-0})"; status=1; fi
if [ "$bad" != "[]" ]; then say "FAILED: images that did not load: $bad"; status=1; fi
if [ "$n" -lt "${MIN_IMAGES:-1}" ]; then say "FAILED: $n images on the page (want at least ${MIN_IMAGES:-1})"; status=1; fi
for t in ${TABLES:-runs rows notok}; do
    grep -q "\"$t\"" <<<"$tables" || { say "FAILED: no table id=\"$t\" (tables: $tables)"; status=1; }
done
latex_note=
rep=$(dirname "$page")
if [ -d "$rep/latex" ] || [ "${LATEX:-0}" = 1 ]; then
    lx=$rep/latex
    for f in numbers.tex verdict.tex reproduction.tex bounds.tex sample.tex; do
        [ -f "$lx/$f" ] || { say "FAILED: latex: no $f in $lx"; status=1; }
    done
    macros=$(grep -c '^\\newcommand{\\mfx[A-Za-z]*}' "$lx/numbers.tex" 2>/dev/null || true)
    # A run without a verdict table (views, seeds-*) says so in numbers.tex instead.
    [ "${macros:-0}" -ge 1 ] || grep -q '^% (none: no row of this run is in a verdict table' "$lx/numbers.tex" \
        || { say "FAILED: latex: numbers.tex defines no \\mfx macro"; status=1; }
    nsvg=0
    for svg in "$rep"/*.svg; do
        [ -f "$svg" ] || continue
        nsvg=$((nsvg + 1))
        pdf=${svg%.svg}.pdf
        if [ ! -f "$pdf" ]; then say "FAILED: latex: $(basename "$svg") has no PDF beside it"; status=1
        elif ! grep -aq '/FontFile2' "$pdf"; then say "FAILED: latex: $(basename "$pdf") embeds no font"; status=1; fi
    done
    if command -v pdflatex >/dev/null; then
        mkdir -p "$work/tex"
        cp -r "$rep"/. "$work/tex/"
        if (cd "$work/tex/latex" && timeout 120 pdflatex -interaction=nonstopmode -halt-on-error sample.tex >"$work/pdflatex.log" 2>&1); then
            latex_note=", LaTeX: $macros macros, $nsvg PDF charts, sample.tex compiles"
        else
            say "FAILED: latex: pdflatex sample.tex failed:"; tail -n 20 "$work/pdflatex.log"; status=1
        fi
    elif [ "${CI:-}" = true ]; then
        say "FAILED: latex: no pdflatex in CI (scripts/setup.sh installs texlive-latex-base texlive-latex-recommended)"; status=1
    else
        latex_note=", LaTeX: $macros macros, $nsvg PDF charts; SKIPPED the pdflatex build (no pdflatex here: apt-get install texlive-latex-base texlive-latex-recommended)"
    fi
fi
if [ "$status" = 0 ]; then
    say "PASSED: $page in $($browser --version 2>/dev/null | head -n 1): $n images loaded, $charts chart layouts pass, tables $tables$latex_note"
fi
exit "$status"
