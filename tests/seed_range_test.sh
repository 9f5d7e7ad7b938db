#!/usr/bin/env bash
# The report seeds (5000–5019, issue 59) belong to docs/results/figures.yaml
# alone: no test, benchmark, tool or script may name a seed >= 5000, so that
# the figures plantscale reports were never tuned or tested on. Fails naming
# file and line. A seed is "named" when a number >= 5000 follows the word
# seed (--seed 5003, .seed = 5001, seeds 5000–5019, kSeed{5002}) on a line.
# usage: seed_range_test.sh SOURCE_DIR
set -uo pipefail
src="$1"
cd "$src" || { echo "FAIL: no source folder '$src'"; exit 1; }

pattern='seeds?[^0-9[:cntrl:]]{0,24}([^0-9.]|^)([5-9][0-9]{3}|[1-9][0-9]{4,})([^0-9]|$)'

# The pattern must find what it is for (a test that cannot fail is none).
for sample in '--seed 5003' 'o.sim.seed = 5001;' 'seeds 5000–5019' 'kSeed{5002}' 'seed=12345'; do
  if ! grep -qiE -- "$pattern" <<<"$sample"; then
    echo "FAIL: the pattern misses '$sample'"
    exit 1
  fi
done
for sample in '--seed 500' 'seed 1000' 'seeds < 40' 'seed 0.5000'; do
  if grep -qiE -- "$pattern" <<<"$sample"; then
    echo "FAIL: the pattern takes '$sample' for a report seed"
    exit 1
  fi
done

failures=0
while IFS= read -r hit; do
  echo "FAIL: $hit: names a report seed (>= 5000); those belong to docs/results/figures.yaml"
  failures=$((failures + 1))
done < <(find tests bench tools app engine evaluation telemetry maps ui .ci plantscale.sh \
           -type f \( -name '*_test.cc' -o -name '*_test.sh' -o -name '*.sh' -o -name '*.py' \
                      -o -path 'tests/*' -o -path 'bench/*' -o -path 'tools/*' -o -path '.ci/*' \) \
           ! -name seed_range_test.sh ! -path '*/corpus/*' ! -path '*/node_modules/*' 2>/dev/null |
         sort | xargs -r grep -nHiE -- "$pattern")

if [[ $failures -ne 0 ]]; then
  echo "report seeds: $failures line(s) name a seed >= 5000"
  exit 1
fi
echo "report seeds: no test, benchmark, tool or script names a seed >= 5000"
