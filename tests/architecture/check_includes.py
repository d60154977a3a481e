#!/usr/bin/env python3
"""The include-level half of hil's layer check (cmake/HilLayers.cmake, docs/architecture.md).

The configure step checks what each target links; this checks what each file includes, so that a
header cannot reach upward without a link saying so (a header-only use links nothing). It reads
the hil_layers.json the configure wrote: every target's layer and source folder, and the table of
what each layer may link.

  check_includes.py BUILD/hil_layers.json    exit 1 listing every upward #include
  check_includes.py --self-test              the check on a made-up tree (it must catch one)

A file belongs to the target whose source folder holds it most closely (diagnosis/truth/ is
hil_contact_truth's, not hil_diagnose's). `#include <hil/NAME/...>` names the module whose
folder has include/hil/NAME/; a generated bus header ("hil_msgs.h", "...PubSubTypes.h") is the
bus types'.
"""
import json
import os
import re
import sys
import tempfile
import unittest

INCLUDE = re.compile(r'^\s*#\s*include\s*([<"])([^>"]+)[>"]', re.M)
SOURCE_EXT = ('.cpp', '.hpp', '.h', '.cc', '.hpp.in')
BUS_GENERATED = re.compile(r'^(builtin_interfaces|std_msgs|geometry_msgs|sensor_msgs|tf2_msgs|diagnostic_msgs|hil_msgs)'
                           r'(PubSubTypes)?\.h$')


def load(path):
    with open(path, encoding='utf-8') as f:
        return json.load(f)


def owners_of_prefixes(targets):
    """hil/NAME -> the set of layers of the targets that provide include/hil/NAME."""
    owners = {}
    for t in targets:
        inc = os.path.join(t['source_dir'], 'include', 'hil')
        if os.path.isdir(inc):
            for name in os.listdir(inc):
                if os.path.isdir(os.path.join(inc, name)):
                    owners.setdefault(name, set()).add(t['layer'])
    return owners


def file_owner(path, dirs):
    """The (source_dir, layer) of the target folder that holds `path` most closely."""
    best = None
    for d, layer in dirs:
        if path.startswith(d + os.sep) and (best is None or len(d) > len(best[0])):
            best = (d, layer)
    return best


def check(layers):
    rules = {k: set(v) for k, v in layers['rules'].items()}
    targets = layers['targets']
    owners = owners_of_prefixes(targets)
    bus_layer = next((t['layer'] for t in targets if t['name'] == 'hil_idl_types'), 'bus')
    root = os.path.normpath(layers.get('source_dir', '/nonexistent'))
    # The top folder defines only flag targets (hil_warnings): its files are no module's. Files
    # under tests/ outside a test target's folder (fuzz targets, install consumers) are tests'.
    dirs = {(os.path.normpath(t['source_dir']), t['layer']) for t in targets}
    dirs = sorted({(d, l) for d, l in dirs if d != root} | {(os.path.join(root, 'tests'), 'tests')})
    # A folder with two targets of different layers (tools/hil: framework and program below it)
    # is checked with the most permissive of them only when they agree; otherwise by each file's
    # closest folder, which is what the build's folders give.
    problems = []
    checked = 0
    for d in sorted({d for d, _ in dirs}):
        for root, subdirs, files in os.walk(d):
            subdirs[:] = [s for s in subdirs if not s.startswith('.') and s != 'build']
            for f in files:
                if not f.endswith(SOURCE_EXT):
                    continue
                path = os.path.join(root, f)
                owner = file_owner(path, dirs)
                if owner is None or owner[0] != d:
                    continue  # a nested target's file: checked from its own folder
                layers_here = {layer for dd, layer in dirs if dd == d}
                allowed = set.union(*(rules[l] for l in layers_here))
                checked += 1
                with open(path, encoding='utf-8', errors='replace') as fh:
                    text = fh.read()
                for m in INCLUDE.finditer(text):
                    inc = m.group(2)
                    line = text.count('\n', 0, m.start()) + 1
                    if inc.startswith('hil/'):
                        parts = inc.split('/')
                        if len(parts) < 3:
                            continue
                        target_layers = owners.get(parts[1])
                        if target_layers is None:
                            problems.append(f'{path}:{line}: includes <{inc}>, which no module provides')
                            continue
                    elif BUS_GENERATED.match(os.path.basename(inc)):
                        target_layers = {bus_layer}
                    else:
                        continue
                    if not target_layers & allowed:
                        what = '/'.join(sorted(layers_here))
                        problems.append(f'{path}:{line}: a {what} file includes <{inc}> '
                                        f'({"/".join(sorted(target_layers))}), which its layer may not use')
    return problems, checked


def main(argv):
    if len(argv) == 2 and argv[1] == '--self-test':
        ok = unittest.main(argv=[argv[0]], exit=False).result.wasSuccessful()
        return 0 if ok else 1
    if len(argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    problems, checked = check(load(argv[1]))
    for p in problems:
        print(p)
    print(f'hil includes: {checked} files checked, {len(problems)} upward includes')
    return 1 if problems else 0


class SelfTest(unittest.TestCase):
    """The check on a made-up tree: a numerics module, a formats module and a nested test folder."""

    def tree(self, numerics_includes):
        tmp = tempfile.mkdtemp()
        def write(rel, text):
            p = os.path.join(tmp, rel)
            os.makedirs(os.path.dirname(p), exist_ok=True)
            with open(p, 'w') as f:
                f.write(text)
        write('num/include/hil/num/a.hpp', '#pragma once\n' + numerics_includes)
        write('num/src/a.cpp', '#include <hil/num/a.hpp>\n')
        write('fmt/include/hil/fmt/b.hpp', '#pragma once\n#include <hil/num/a.hpp>\n')
        write('fmt/sub/src/c.cpp', '#include <hil/fmt/b.hpp>\n#include "hil_msgs.h"\n')
        return {
            'rules': {'numerics': ['numerics'], 'formats': ['numerics', 'formats', 'bus'], 'bus': ['bus'],
                      'tests': ['numerics', 'formats', 'bus', 'tests']},
            'targets': [
                {'name': 'num', 'layer': 'numerics', 'source_dir': os.path.join(tmp, 'num')},
                {'name': 'fmt', 'layer': 'formats', 'source_dir': os.path.join(tmp, 'fmt')},
                {'name': 'hil_idl_types', 'layer': 'bus', 'source_dir': os.path.join(tmp, 'bus')},
                {'name': 'sub', 'layer': 'tests', 'source_dir': os.path.join(tmp, 'fmt', 'sub')},
            ]}

    def test_a_clean_tree_passes(self):
        problems, checked = check(self.tree(''))
        self.assertEqual(problems, [])
        self.assertEqual(checked, 4)

    def test_a_numerics_header_reaching_a_format_is_named(self):
        problems, _ = check(self.tree('#include <hil/fmt/b.hpp>\n'))
        self.assertEqual(len(problems), 1)
        self.assertIn('a.hpp:2: a numerics file includes <hil/fmt/b.hpp> (formats)', problems[0])

    def test_a_generated_bus_header_counts_as_the_bus(self):
        problems, _ = check(self.tree('#include "geometry_msgsPubSubTypes.h"\n'))
        self.assertEqual(len(problems), 1)
        self.assertIn('(bus)', problems[0])

    def test_an_unknown_module_is_named(self):
        problems, _ = check(self.tree('#include <hil/nothing/x.hpp>\n'))
        self.assertEqual(len(problems), 1)
        self.assertIn('which no module provides', problems[0])


if __name__ == '__main__':
    sys.exit(main(sys.argv))
