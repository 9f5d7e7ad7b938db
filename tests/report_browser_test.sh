#!/usr/bin/env bash
# The report looked at in a real browser (issue 36): a short simulated run's
# report opened in headless Chromium; every picture of index.html loaded (no
# broken image, each at least 100 px wide), the page between 1,000 and
# 40,000 px tall, and a screenshot of the page written
# (WORK/page.png). Skipped (77) only when chromium is not installed.
set -uo pipefail
# shellcheck source=cli_lib.sh
source "$(dirname "$0")/cli_lib.sh"
plantscale="$1"
work="$2"
rm -rf "$work" && mkdir -p "$work"
browser=$(command -v chromium || command -v chromium-browser || true)
if [[ -z "$browser" ]]; then echo "skip: chromium is not installed (apt-get install chromium)"; exit 77; fi

log="$work/run.lcmlog"
"$plantscale" simulate --preset field --length-m 12 --publish --fast --lcm-url memq:// --quiet \
  --log "$log" >/dev/null 2>&1 || fail "simulate exited $?"
"$plantscale" report "$log" --out "$work/report" >/dev/null || fail "report exited $?"
# A page beside the report that loads it in a frame and writes what it sees.
cat >"$work/check.html" <<'HTML'
<!DOCTYPE html><html><body><pre id="out">pending</pre>
<iframe id="f" src="report/index.html" style="width:1280px;height:900px"></iframe>
<script>
document.getElementById('f').addEventListener('load', () => {
  const d = document.getElementById('f').contentDocument;
  const imgs = Array.from(d.images);
  const broken = imgs.filter(i => !i.complete || i.naturalWidth < 100).map(i => i.getAttribute('src'));
  document.getElementById('out').textContent =
    'images=' + imgs.length + ' broken=' + broken.length + ' [' + broken.join(',') + '] height=' +
    d.documentElement.scrollHeight;
});
</script></body></html>
HTML
flags=(--headless --no-sandbox --disable-gpu --allow-file-access-from-files --virtual-time-budget=15000)
result=$("$browser" "${flags[@]}" --dump-dom "file://$work/check.html" 2>/dev/null | grep -m1 -oE 'images=[0-9]+ broken=[0-9]+ \[[^]]*\] height=[0-9]+')
echo "chromium: $result"
images=$(grep -oE 'images=[0-9]+' <<<"$result" | cut -d= -f2)
broken=$(grep -oE 'broken=[0-9]+' <<<"$result" | cut -d= -f2)
height=$(grep -oE 'height=[0-9]+' <<<"$result" | cut -d= -f2)
[[ -n "$images" && "$images" -ge 5 ]] || fail "fewer than 5 pictures in the page ($result)"
[[ "$broken" == 0 ]] || fail "broken pictures: $result"
[[ -n "$height" && "$height" -ge 1000 && "$height" -le 40000 ]] || fail "page height out of 1000..40000 px: $result"
"$browser" "${flags[@]}" --hide-scrollbars --window-size=1280,"${height:-4000}" \
  --screenshot="$work/page.png" "file://$work/report/index.html" >/dev/null 2>&1
[[ -s "$work/page.png" ]] || fail "no screenshot of the page"
finish "report in a browser"
