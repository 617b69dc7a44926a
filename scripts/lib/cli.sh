# The command-line helpers of the bash scripts in scripts/, sourced by each before it changes to the
# repository's root: a relative path on the command line is then the caller's, as with any other
# command, not the root's. The script sets $prog (its name, for its one-line errors) first.
cli_caller_dir=$PWD

# An option's value, or one line and exit 2 when it has none.
value() {
  if [ $# -lt 2 ] || [ -z "$2" ]; then echo "$prog: $1 needs a value (see --help)" >&2; exit 2; fi
  printf '%s' "$2"
}

# A file or directory option's value, made absolute against the directory the script was started in.
path_value() {
  local v
  v=$(value "$@") || exit 2
  case "$v" in
    /*) printf '%s' "$v" ;;
    *) printf '%s/%s' "${cli_caller_dir%/}" "$v" ;;  # from /: /x, not //x
  esac
}
