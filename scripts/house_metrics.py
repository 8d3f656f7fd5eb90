#!/usr/bin/env python3
"""House metrics: the heuristics the architecture review measures, one tool for before and after.

Prints (tests/, fuzz/ and build trees excluded):
  cli_lines / cli_nonverb_lines  lines in cli/; lines in cli/ files that are not a verb's command
                                 line (file heuristic: every file except *_verb.*, main.cc,
                                 command_line.*, option_values.*, fit_option_args.*)
  functions_over_100 / _over_80  function definitions longer than N lines (universal-ctags
                                 `end` field; declarations and lambdas are not counted)
  readme_lines                   README.md
  rec709_files                   source files holding the Rec.709 luminance weight 0.2126
  kpi_definitions                files defining a kPi constant
  outside_refs                   relative paths that climb out of the repository (a user's
                                 clone has nothing beside it) and issue numbers, in sources,
                                 build files and scripts
Usage: scripts/house_metrics.py [--list]   (--list prints the long functions)
"""
import json, os, re, subprocess, sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SRC_EXT = ('.cc', '.h', '.glsl', '.comp', '.cpp', '.hpp')
SKIP_DIRS = {'.git', 'tests', 'fuzz', 'build', 'build-asan', 'build-fuzz', 'node_modules', 'cache'}
VERB_FILE = re.compile(r'(_verb\.(cc|h)|^main\.cc|^command_line\.(cc|h)|^option_values\.(cc|h)|^fit_option_args\.(cc|h))$')


def sources():
    for d, dirs, files in os.walk(ROOT):
        dirs[:] = [x for x in dirs if x not in SKIP_DIRS and not x.startswith('build')]
        for f in files:
            if f.endswith(SRC_EXT) or '.glsl' in f:
                yield os.path.join(d, f)


def count_lines(path):
    with open(path, errors='replace') as fh:
        return sum(1 for _ in fh)


def long_functions(files):
    out = subprocess.run(['ctags', '--output-format=json', '--fields=+ne', '--kinds-C++=f',
                          '--language-force=C++', '-f', '-'] + files,
                         capture_output=True, text=True, check=True).stdout
    found = []
    for line in out.splitlines():
        tag = json.loads(line)
        if tag.get('kind') == 'function' and 'end' in tag:
            n = tag['end'] - tag['line'] + 1
            found.append((n, os.path.relpath(tag['path'], ROOT), tag['name']))
    return sorted(found, reverse=True)


# A relative path that starts with "../" (not one joined to a variable or a folder).
CLIMB = re.compile(r'(?<![\w/$}.])(?:\.\./)+[A-Za-z0-9_][\w.-]*')
ISSUE = re.compile(r'[Ii]ssue #?[0-9]+')


def outside_refs(path, text):
    """Climbs that leave the repository, resolved from the file's folder and, for scripts and
    build files (run from the root), from the root too; and issue numbers."""
    run_from_root = path.endswith(('.sh', '.py', '.cmake', 'CMakeLists.txt'))
    bases = [os.path.dirname(path)] + ([ROOT] if run_from_root else [])

    def leaves(ref):
        return any(not os.path.realpath(os.path.join(b, ref)).startswith(ROOT + os.sep) for b in bases)
    return sum(1 for m in CLIMB.finditer(text) if leaves(m.group(0))) + len(ISSUE.findall(text))


def main():
    files = sorted(sources())
    cc = [f for f in files if f.endswith(('.cc', '.cpp', '.h', '.hpp'))]
    cli = [f for f in files if os.path.relpath(f, ROOT).startswith('cli' + os.sep)]
    cli_lines = sum(count_lines(f) for f in cli)
    nonverb = sum(count_lines(f) for f in cli if not VERB_FILE.search(os.path.basename(f)))
    funcs = long_functions(cc)
    text = {f: open(f, errors='replace').read() for f in files}
    other = [os.path.join(ROOT, p) for p in ('CMakeLists.txt',)]
    for d, dirs, fs in os.walk(ROOT):
        dirs[:] = [x for x in dirs if x not in SKIP_DIRS and not x.startswith('build')]
        for f in fs:
            if f in ('CMakeLists.txt',) or f.endswith(('.cmake', '.sh')):
                other.append(os.path.join(d, f))
    for f in set(other):
        if os.path.exists(f):
            text[f] = open(f, errors='replace').read()
    for f in os.listdir(os.path.join(ROOT, 'scripts')):
        if f.endswith('.py'):
            text[os.path.join(ROOT, 'scripts', f)] = open(os.path.join(ROOT, 'scripts', f), errors='replace').read()
    metrics = {
        'cli_lines': cli_lines,
        'cli_nonverb_lines': nonverb,
        'functions_over_100': sum(1 for n, _, _ in funcs if n > 100),
        'functions_over_80': sum(1 for n, _, _ in funcs if n > 80),
        'readme_lines': count_lines(os.path.join(ROOT, 'README.md')),
        'rec709_files': sum(1 for f in files if '0.2126' in text[f]),
        'kpi_definitions': sum(1 for f in files if re.search(r'\bkPi\s*=', text[f])),
        'outside_refs': sum(outside_refs(f, t) for f, t in text.items()),
    }
    print(json.dumps(metrics, indent=2))
    if '--list' in sys.argv:
        for n, path, name in funcs:
            if n > 80:
                print(f'{n:5d}  {path}  {name}')


if __name__ == '__main__':
    main()
