#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
# check-refs: skip-file (this test writes a fixture tree full of dangling names)
"""tools/scripts/check-refs on a small fixture tree: it must report each dangling
file, document, section and heading reference (file:line) and nothing that
resolves, exit 1 for a dangling tree, 0 once fixed, 2 on a usage error.

usage: test_check_refs.py CHECK_REFS
"""
import os
import subprocess
import sys
import tempfile

checker = sys.argv[1]
fails = []

FILES = {
    "docs/METHOD.md": """# Method

## 1. Conventions
### 1.1 Transform
Own section: §1.1 and §2.
## 2. Regressor
1. first item
2. second item
""",
    "README.md": """# fixture
## Method, and more
See docs/METHOD.md §1 and §2.2.
""",  # §2.2 is the second numbered item of section 2
    "src/a.c": """/* Stage one (docs/METHOD.md §1.1), the tables (§2) and
 * their roots (§3).
 * Declared in src/bg_missing.h;
 * derived in MATH.md;
 * see README "Method", README "No such heading".
 * also src/a.c, ../README.md and docs/METHOD.md §2.3. */
#include <sys/types.h>
#include "b.h"
/* https://example.com/src/gone.c, results/summary.md, build/x.c, fixture_only.h */
/* docs/METHOD.md §9 */
/* check-refs: ignore src/ignored.h */
""",
    "src/b.h": "/* b */\n",
    "tools/scripts/check-refs.allow": "results/*   generated\nbuild*   build output\nfixture_only.h   test\n",
}
EXPECTED = {
    "src/a.c:2: §3: docs/METHOD.md has no section 3",
    "src/a.c:3: names 'src/bg_missing.h', which does not exist",
    "src/a.c:4: names 'MATH.md'; no document of that name in the tree",
    "src/a.c:5: README.md has no heading \"No such heading\"",
    "src/a.c:6: §2.3: docs/METHOD.md has no section 2.3",
    "src/a.c:10: §9: docs/METHOD.md has no section 9",
}


def run(root, *args):
    p = subprocess.run(["/usr/bin/python3", checker, "--root", root] + list(args),
                       capture_output=True, text=True)
    return p.returncode, p.stdout, p.stderr


with tempfile.TemporaryDirectory() as root:
    for rel, text in FILES.items():
        path = os.path.join(root, rel)
        os.makedirs(os.path.dirname(path), exist_ok=True)
        with open(path, "w", encoding="utf-8") as fh:
            fh.write(text)

    rc, out, err = run(root)
    got = {line for line in out.splitlines() if not line.startswith("check-refs:")}
    if rc != 1:
        fails.append("dangling tree: exit %d, expected 1\n%s%s" % (rc, out, err))
    for e in sorted(EXPECTED - got):
        fails.append("not reported: " + e)
    for g in sorted(got - EXPECTED):
        fails.append("reported but should resolve: " + g)

    # fix every dangling reference: the tree must then pass
    with open(os.path.join(root, "src/bg_missing.h"), "w") as fh:
        fh.write("\n")
    with open(os.path.join(root, "docs/MATH.md"), "w") as fh:
        fh.write("# other\n")
    with open(os.path.join(root, "docs/METHOD.md"), "a") as fh:
        fh.write("### 2.3 Sub\n## 3. Third\n## 9. Ninth\n")
    with open(os.path.join(root, "README.md"), "a") as fh:
        fh.write("## No such heading, after all\n")
    rc, out, err = run(root)
    if rc != 0:
        fails.append("fixed tree: exit %d, expected 0\n%s%s" % (rc, out, err))

    rc, out, err = run(root, "--no-such-option")
    if rc != 2:
        fails.append("usage error: exit %d, expected 2" % rc)

for f in fails:
    print("FAIL:", f)
print("test_check_refs: %s" % ("FAILED" if fails else "passed"))
sys.exit(1 if fails else 0)
