#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""Every default the documentation states is the code's: imest_config_default()
against

  * the comments of imest_config_t (and imest_inverter_t) in include/imest/imest.h:
    "(default X)", "(default A .. B)" for a field and the next one, "(X = ..., default)",
    "negative: ... (default)", "(default NAME)" for an enum;
  * imest-replay --help: "(default X)" of every option that sets a config field
    (the option table k_numeric of tools/replay/replay_options.c maps options to fields);
  * the comments of imest_tracker_config_t in include/imest/imest_tracker.h against
    imest_tracker_config_default() (every field but the caller's nominal T_R must state one);
  * the comments of imest_temperature_config_t in include/imest/imest_temperature.h against
    imest_temperature_config_default() (every field but the caller's references and L_R);
  * README.md: "`field` (default X)" and "(default X %)";
  * the instance size: README.md, fw/README.md and include/imest/imest_instance.h state
    sizeof(imest_t) measured on the Cortex-M4F/M7; it is checked against this host's
    sizeof (the same on x86-64: every member is 32-bit; if a port makes them differ, the
    documents must say which figure is which).

It also checks that the probe program lists every field the header declares, so a
new field cannot go unchecked, and that each field comment is followed by its field
(not by another field's comment). A documented value is compared as float32 with the
code's. Fails naming the place, the field, the documented and the code's value.

usage: test_documented_defaults.py CONFIG_DEFAULTS_BIN REPLAY_BIN SOURCE_DIR
Exit status: 0 all agree; 1 a disagreement (each listed); 2 usage error.
"""
import os
import re
import struct
import subprocess
import sys

UNITS = {"": 1.0, "s": 1.0, "ms": 1e-3, "us": 1e-6, "Hz": 1.0, "rad/s": 1.0, "A": 1.0, "V": 1.0,
         "ohm": 1.0, "%": 0.01}
NUM = r"[-+]?\d+(?:\.\d*)?(?:e[-+]?\d+)?"
UNIT = r"(?:\s*(ms|us|s|Hz|rad/s|A|V|ohm|%)(?![\w/]))?"


def f32(x):
    return struct.unpack("<f", struct.pack("<f", x))[0]


def value(num, unit):
    return float(num) * UNITS[unit or ""]


ORPHANS = []


def header_fields(text, struct="imest_config_t"):
    """[(field, doc)] of a config struct in declaration order, imest_inverter_t's as inverter.*"""

    def body(name):
        end = text.index("} %s;" % name)
        start = text.rindex("typedef struct {", 0, end)
        return text[start + len("typedef struct {"):end]

    def parse(src, prefix=""):
        out, pending = [], ""
        tok = re.compile(r"/\*\*<(.*?)\*/|/\*\*(.*?)\*/|/\*(.*?)\*/|([A-Za-z_][\w ]*?)\s+(\w+)\s*(?:\[\w+\])?\s*;", re.S)
        for m in tok.finditer(src):
            if m.group(1) is not None:  # trailing: the previous field's
                if out:
                    out[-1] = (out[-1][0], out[-1][1] + " " + m.group(1))
            elif m.group(2) is not None:
                if pending:  # two field comments in a row: the first has lost its field
                    ORPHANS.append(pending.strip()[:70])
                pending = m.group(2)
            elif m.group(3) is not None:
                continue  # a group heading
            else:
                typ, name = m.group(4).strip(), m.group(5)
                if typ == "imest_inverter_t":
                    out += parse(body("imest_inverter_t"), name + ".")
                else:
                    out.append((prefix + name, pending))
                pending = ""
        return out

    return [(f, re.sub(r"\s*\*\s*", " ", d)) for f, d in parse(body(struct))]


def header_claims(fields):
    """{field: documented} from the comments: a float, an enum name, or '<0'."""
    claims = {}
    for k, (field, doc) in enumerate(fields):
        m = re.search(r"default\s+(%s)%s\s*\.\.\s*(%s)%s" % (NUM, UNIT, NUM, UNIT), doc)
        if m:
            claims[field] = value(m.group(1), m.group(2))
            if k + 1 < len(fields):
                claims[fields[k + 1][0]] = value(m.group(3), m.group(4))
            continue
        m = re.search(r"default\s+(%s)%s" % (NUM, UNIT), doc)
        if m:
            claims[field] = value(m.group(1), m.group(2))
            continue
        m = re.search(r"\((%s)[^()]*?,\s*default\)" % NUM, doc)
        if m:
            claims[field] = float(m.group(1))
            continue
        m = re.search(r"default\s+([A-Z][A-Z_]+)\b", doc)
        if m:
            claims[field] = m.group(1)
            continue
        if re.search(r"negative:[^()]*\(default\)", doc):
            claims[field] = "<0"
    return claims


def help_claims(help_text):
    """[(option, documented)] of "(default X)" in imest-replay --help."""
    blocks, cur = [], None
    for line in help_text.splitlines():
        if re.match(r"^  -", line):
            cur = [line]
            blocks.append(cur)
        elif cur is not None and re.match(r"^ {6,}\S", line):
            cur.append(line)
        else:
            cur = None
    out = []
    for b in blocks:
        head = re.split(r"\s{2,}", b[0].strip(), maxsplit=1)[0]
        opts = re.findall(r"--[\w-]+", head)
        text = " ".join(s.strip() for s in b)
        m = re.search(r"default\s+(%s)\s*\.\.\s*(%s)" % (NUM, NUM), text)
        if m and len(opts) == 2:
            out += [(opts[0], float(m.group(1))), (opts[1], float(m.group(2)))]
            continue
        m = re.search(r"default\s+min\((%s)," % NUM, text)  # --speed-limit: min(config, 2 x fs)
        if m:
            out.append((opts[0], float(m.group(1))))
            continue
        m = re.search(r"default\s+(%s)" % NUM, text)
        if m:
            out.append((opts[0], float(m.group(1))))
            continue
        m = re.search(r"default\s+(none|off)\b", text)
        if m:
            out.append((opts[0], 0.0))
    return out


def main():
    if len(sys.argv) != 4:
        print(__doc__, file=sys.stderr)
        return 2
    probe, replay, src = sys.argv[1:4]
    code = {}
    for line in subprocess.run([probe], check=True, capture_output=True, text=True).stdout.splitlines():
        name, val = line.rsplit(" ", 1)
        code[name] = val
    fails, checked = [], []

    def compare(where, field, doc):
        if field not in code:
            fails.append("%s: %s: documented %r, but the probe does not print the field" % (where, field, doc))
            return
        have = code[field]
        if doc == "<0":
            ok = float(have) < 0
        elif isinstance(doc, str):
            ok = have == doc
        else:
            ok = f32(doc) == f32(float(have))
        checked.append((where, field, doc, have))
        if not ok:
            fails.append("%s: %s: documented %s, the code's default (imest_config_default(), imest_tracker_config_default()) is %s" % (where, field, doc, have))

    # 1. the header's comments
    with open(os.path.join(src, "include/imest/imest.h")) as f:
        fields = header_fields(f.read())
    declared = [f for f, _ in fields]
    probed = [n for n in code if n != "sizeof imest_t" and not n.startswith(("tracker.", "temperature."))]
    for f in declared:
        if f not in code:
            fails.append("include/imest/imest.h declares %s: add it to test/tools/config_defaults.c" % f)
    for f in probed:
        if f not in declared:
            fails.append("test/tools/config_defaults.c prints %s, which imest_config_t does not declare" % f)
    for o in ORPHANS:
        fails.append("include/imest/imest.h: a field comment followed by another, not by its field "
                     "(which field does it document?): '%s ...'" % o)
    claims = header_claims(fields)
    for f, doc in claims.items():
        compare("include/imest/imest.h", f, doc)

    # 1b. the T_R tracker's header (imest_tracker.h): every field but the caller's nominal
    with open(os.path.join(src, "include/imest/imest_tracker.h")) as f:
        tfields = [("tracker." + n, d) for n, d in header_fields(f.read(), "imest_tracker_config_t")]
    tclaims = header_claims(tfields)
    for f, _ in tfields:
        if f != "tracker.tr_nominal_s" and f not in tclaims:
            fails.append("include/imest/imest_tracker.h: %s states no default" % f)
        if f != "tracker.tr_nominal_s" and f not in code:
            fails.append("include/imest/imest_tracker.h declares %s: add it to "
                         "test/tools/config_defaults.c" % f)
    for f, doc in tclaims.items():
        compare("include/imest/imest_tracker.h", f, doc)

    # 1c. the temperature module's header (imest_temperature.h): every field but the caller's
    with open(os.path.join(src, "include/imest/imest_temperature.h")) as f:
        mfields = [("temperature." + n, d) for n, d in header_fields(f.read(), "imest_temperature_config_t")]
    callers = {"temperature." + n for n in ("t_ref_c", "rs_ref_ohm", "tr_ref_s", "lr_h")}
    mclaims = header_claims(mfields)
    if len(mfields) != 11:
        fails.append("include/imest/imest_temperature.h: %d config fields parsed, expected 11" % len(mfields))
    for f, _ in mfields:
        if f not in callers and f not in mclaims:
            fails.append("include/imest/imest_temperature.h: %s states no default" % f)
        if f not in callers and f not in code:
            fails.append("include/imest/imest_temperature.h declares %s: add it to "
                         "test/tools/config_defaults.c" % f)
    for f, doc in mclaims.items():
        if f not in callers:
            compare("include/imest/imest_temperature.h", f, doc)

    # 2. imest-replay --help, through replay's option table
    with open(os.path.join(src, "tools/replay/replay_options.c")) as f:
        options_c = f.read()
    table = dict(re.findall(r'\{"(--[\w-]+)",\s*"([\w.]+)",\s*offsetof', options_c))
    table["--speed-limit"] = "speed_limit_rad_s"
    if len(table) < 20:
        fails.append("tools/replay/replay_options.c: option table not found (%d entries)" % len(table))
    given = re.search(r"#define INVERTER_UNCERTAINTY_GIVEN\s+(%s)f?" % NUM, options_c)
    help_text = subprocess.run([replay, "--help"], check=True, capture_output=True, text=True).stdout
    helped = help_claims(help_text)
    for opt, doc in helped:
        if opt not in table:
            continue  # replay's own option (--fs, --i-limit ...), no config field
        if opt == "--inverter-uncertainty":
            # replay's own default when an inverter model is given; the config's (unknown) otherwise
            if not given or f32(float(given.group(1))) != f32(doc):
                fails.append("imest-replay --help: --inverter-uncertainty: documented %s, replay's "
                             "INVERTER_UNCERTAINTY_GIVEN is %s" % (doc, given.group(1) if given else "missing"))
            compare("imest-replay --help (--inverter-uncertainty without a model: unknown)",
                    "inverter.uncertainty", "<0")
            continue
        compare("imest-replay --help (%s)" % opt, table[opt], doc)
    if len([o for o, _ in helped if o in table]) < 12:
        fails.append("imest-replay --help: only %d defaults found: has the help's layout changed?" % len(helped))

    # 3. README.md: "`field` (default X)"
    with open(os.path.join(src, "README.md")) as f:
        readme = f.read()
    for m in re.finditer(r"`([a-z0-9_]+)`\s*\(default (%s)%s" % (NUM, UNIT), readme):
        if m.group(1) in code:
            compare("README.md", m.group(1), value(m.group(2), m.group(3)))

    # 4. the instance size
    size = int(code["sizeof imest_t"])
    with open(os.path.join(src, "fw/README.md")) as f:
        fw = f.read()
    with open(os.path.join(src, "include/imest/imest_instance.h")) as f:
        inst = f.read()
    stated = [("README.md", m) for m in re.findall(r"(\d+) B RAM per instance", readme)]
    stated += [("README.md (example)", m) for m in re.findall(r"/\* (\d+) B on a Cortex-M4F", readme)]
    stated += [("fw/README.md", m) for m in re.findall(r"`sizeof\(imest_t\)`\) \|[^|]*\| (\d+) ", fw)]
    stated += [("include/imest/imest_instance.h", m) for m in re.findall(r"sizeof\(imest_t\) is (\d+) B", inst)]
    if len(stated) < 4:
        fails.append("sizeof(imest_t): found %d statements of it, expected 4 (README.md x2, fw/README.md, "
                     "imest_instance.h)" % len(stated))
    for where, m in stated:
        checked.append((where, "sizeof(imest_t)", int(m), size))
        if int(m) != size:
            fails.append("%s: sizeof(imest_t) stated %s B (the Cortex-M figure), this host's is %d B: "
                         "remeasure with tools/firmware-budget, or state both" % (where, m, size))

    for where, field, doc, have in checked:
        print("ok   %-60s %-24s documented %-12s code %s" % (where, field, doc, have))
    for f in fails:
        print("FAIL " + f)
    undocumented = [f for f in declared if f not in claims]
    print("%d statements checked, %d failures; fields without a stated default in imest.h: %s"
          % (len(checked), len(fails), ", ".join(undocumented)))
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())
