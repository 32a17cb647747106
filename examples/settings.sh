# The learning loop's settings, declared once in settings.txt: their defaults and checks for
# learn.sh, the names examples/Makefile accepts on its command line, the table `make help`
# prints. Sourced (after common.sh, whose method_k and run_label the defaults use).
settings_dir=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)

# settings.txt's rows, one "name|default|check|meaning" a line, without padding or comments.
settings_rows() {
  local name default check meaning
  while IFS='|' read -r name default check meaning; do
    [[ $name =~ ^[A-Z] ]] || continue
    default=${default# } check=${check# } meaning=${meaning# }
    echo "${name% }|${default% }|${check% }|${meaning}"
  done < "$settings_dir/settings.txt"
}

# The names settings.txt declares, and the variables examples/Makefile assigns or reads (its
# task lists, budgets, campaign seeds): every name make's command line may set.
make_variable_names() {
  { sed -n 's/^\(export \)\{0,1\}\([A-Z][A-Z0-9_]*\) *[:?+]\{0,1\}=.*/\2/p' "$settings_dir/Makefile"
    grep -o '\$([A-Z][A-Z0-9_]*)' "$settings_dir/Makefile" | tr -d '$()'; } | sort -u
}

# For each NAME that is not in KNOWN (a file of names), "NAME" and the known name nearest to it
# (edit distance at most 2, 1 for names of 5 letters or fewer, and the same first letter: a slip
# of the first letter is rare, while the system's own variables often differ from a setting
# just there, as ASAN_OPTIONS and LSAN_OPTIONS from PLAN_OPTIONS), or "-": one pair a line.
nearest_names() {  # KNOWN_FILE NAME...
  local known=$1; shift
  awk -v names="$*" '
    function distance(a, b,    i, j, la, lb, d, cost) {
      la = length(a); lb = length(b)
      for (i = 0; i <= la; i++) d[i, 0] = i
      for (j = 0; j <= lb; j++) d[0, j] = j
      for (i = 1; i <= la; i++)
        for (j = 1; j <= lb; j++) {
          cost = substr(a, i, 1) != substr(b, j, 1)
          d[i, j] = d[i - 1, j] + 1
          if (d[i, j - 1] + 1 < d[i, j]) d[i, j] = d[i, j - 1] + 1
          if (d[i - 1, j - 1] + cost < d[i, j]) d[i, j] = d[i - 1, j - 1] + cost
        }
      return d[la, lb]
    }
    { known[$1] = 1 }
    END {
      n = split(names, list, " ")
      for (k = 1; k <= n; k++) {
        name = list[k]
        if (name in known) continue
        best = "-"; bestd = length(name) <= 5 ? 2 : 3
        for (other in known) {
          if (substr(other, 1, 1) != substr(name, 1, 1)) continue
          dd = distance(name, other); if (dd < bestd || (dd == bestd && other < best)) { best = other; bestd = dd }
        }
        print name, best
      }
    }' "$known"
}

# A temporary file of every name a setting may have: settings.txt's and the Makefile's.
known_names_file() {
  local file; file=$(mktemp)
  { settings_rows | cut -d'|' -f1; make_variable_names; } > "$file"
  echo "$file"
}

# Names given on make's command line that are neither settings nor the Makefile's variables:
# one line naming the first and the nearest known name, or nothing.
settings_unknown_make_names() {  # NAME...
  local known; known=$(known_names_file)
  local name nearest
  read -r name nearest < <(nearest_names "$known" "$@") || true
  rm -f "$known"
  [ -n "${name:-}" ] || return 0
  if [ "$nearest" = - ]; then echo "$name is not a setting of examples/ (see make -C examples help)"
  else echo "$name is not a setting of examples/ (did you mean $nearest?)"; fi
}

# Whether VALUE passes CHECK (settings.txt's words); the expectation in words otherwise.
setting_problem() {  # VALUE CHECK
  local value=$1 check=$2
  case $check in
    text) return 0 ;;
    size) [[ $value =~ ^[1-9][0-9]{0,4}x[1-9][0-9]{0,4}$ ]] || echo "expected WIDTHxHEIGHT in pixels" ;;
    ints) [[ $value =~ ^([0-9]{1,9}(,[0-9]{1,9})*)?$ ]] || echo "expected whole numbers, comma-separated" ;;
    "one of "*)
      [[ ", ${check#one of }, " == *", $value, "* ]] || echo "expected one of ${check#one of }" ;;
    "real "*)
      local range=${check#real }
      [[ $value =~ ^[0-9]*\.?[0-9]+([eE][-+]?[0-9]+)?$ ]] \
        && awk -v v="$value" -v lo="${range%..*}" -v hi="${range#*..}" 'BEGIN { exit !(v + 0 >= lo + 0 && v + 0 <= hi + 0) }' \
        || echo "expected a number from ${range%..*} to ${range#*..}" ;;
    int\>=*)
      local low=${check#int>=} or=""
      [[ $low == *" or "* ]] && or=${low#* or } low=${low%% or *}
      if [ -n "$or" ] && [ "$value" = "$or" ]; then return 0; fi
      [[ $value =~ ^[0-9]{1,15}$ ]] && (( 10#$value >= low )) \
        || echo "expected a whole number of at least $low${or:+ or $or}" ;;
    *) echo "settings.txt: unknown check '$check'" ;;
  esac
}

# learn.sh's settings: each unset one takes its default, in settings.txt's order (a default may
# use those above it), every one is checked, and an environment variable that is not a setting
# but nearly the name of one (a misspelling, which would be ignored) is refused. One line and
# exit status 2 on the first problem, before anything of the run starts.
settings_load() {  # PROGRAM
  local name default check meaning value problem rows
  rows=$(settings_rows)
  while IFS='|' read -r name default check meaning; do
    if [ -z "${!name:-}" ]; then
      eval "value=\"$default\""
      printf -v "$name" '%s' "$value"
    fi
    export "${name?}"
    problem=$(setting_problem "${!name}" "$check")
    if [ -n "$problem" ]; then
      echo "$1: $name=${!name}: $problem ($meaning)" >&2
      exit 2
    fi
  done <<< "$rows"
  local known; known=$(known_names_file)
  local nearest
  # Only names that look like settings: upper case, and near one (others are the system's).
  read -r name nearest < <(nearest_names "$known" $(compgen -e | grep -E '^[A-Z][A-Z0-9_]*$') | awk '$2 != "-"') || true
  rm -f "$known"
  if [ -n "${nearest:-}" ]; then
    echo "$1: $name is not a setting (did you mean $nearest?); see make -C examples help" >&2
    exit 2
  fi
}

# The table of settings as make help and docs/learning-loop.md show it (markdown).
settings_table() {
  echo "| setting | default | check | meaning |"
  echo "|---|---|---|---|"
  settings_rows | while IFS='|' read -r name default check meaning; do
    echo "| \`$name\` | ${default:+\`$default\`} | $check | $meaning |"
  done
}
