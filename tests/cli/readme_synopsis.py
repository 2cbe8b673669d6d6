"""README's command-line synopsis names every option of every subcommand (it once left out
`render --pathlines`, `--pathline-radius`, `stats --lod`). The options come from the CLI's own help
(`raypc CMD --help`); a command's synopsis is its lines in README's "Command line" block, from
`raypc CMD` to the next command. Options of an option group that the synopsis covers in words
("every option of raypc preprocess", "every option of raypc serve") are checked there.

Usage: readme_synopsis.py RAYPC README.md"""
import re
import subprocess
import sys

raypc, readme = sys.argv[1], open(sys.argv[2]).read()
block = readme.split("## Command line", 1)[1].split("```", 2)[1]
synopsis = {}
for line in block.splitlines():
    m = re.match(r"raypc ([a-z-]+)", line)
    if m:
        current = m.group(1)
    if line.strip():
        synopsis[current] = synopsis.get(current, "") + line + "\n"


def options(command):
    """The options of `raypc COMMAND --help`, each as the set of its names ({"-o", "--output"})."""
    text = subprocess.run([raypc, command, "--help"], capture_output=True, text=True, check=True).stdout
    found = []
    for line in text.splitlines():
        names = line.strip().split("  ")[0] if line.startswith("  ") else ""  # "-t,--time TEXT"
        aliases = set(re.findall(r"(?<![\w-])(--?[a-z][a-z0-9-]*)", names.split(" ")[0]))
        if any(a.startswith("--") for a in aliases) and "--help" not in aliases:
            found.append(aliases)
    return found


def named(alias, text):
    return re.search(r"(?<![\w-])" + re.escape(alias) + r"(?![\w-])", text) is not None


failures = []
commands = sorted(synopsis)
for command in commands:
    text = synopsis[command]
    # "every option of raypc X" (or "every reader option of raypc X") covers X's options in words
    covering = re.findall(r"every (?:[a-z]+ )?option of raypc ([a-z-]+)", text)
    covered = [a for other in covering for a in options(other)]
    for aliases in options(command):
        if any(named(a, text) for a in aliases) or aliases in covered:
            continue
        failures.append(f"raypc {command} {' / '.join(sorted(aliases))}")
help_text = subprocess.run([raypc, "--help"], capture_output=True, text=True).stdout
listed = set(re.findall(r"^  ([a-z][a-z-]*)\s", help_text, re.M))
for command in sorted(listed - set(commands)):
    failures.append(f"raypc {command}: no synopsis line")
if failures:
    print("README's command-line synopsis lacks:\n  " + "\n  ".join(failures))
    sys.exit(1)
print(f"README's synopsis names every option of {len(commands)} commands")
