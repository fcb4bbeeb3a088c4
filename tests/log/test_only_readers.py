"""The codecs of ``lfdfuse/log/`` are the only readers of log messages.

The rule, walked over the package's sources: a module outside ``lfdfuse/log/`` that parses JSON
(``json.load``/``json.loads``/``orjson.loads``, however imported) must not also touch log
messages, i.e. import ``iter_messages``/``iter_raw``/``make_reader`` (ours or mcap's) or name a
``/lfd/`` channel. Parsing other JSON (a client's Twist, a script, a report file, a schema) is
fine; parsing a message's payload is the job of its decoder in ``lfdfuse/log/``.
"""

from __future__ import annotations

import ast

from tests.conftest import ROOT

PACKAGE = ROOT / "lfdfuse"
LOG = PACKAGE / "log"
PARSERS = {("json", "load"), ("json", "loads"), ("orjson", "loads")}
MESSAGE_READERS = {"iter_messages", "iter_raw", "make_reader"}

#: offenders whose fix belongs to another change (none today)
PENDING: set[str] = set()


def offends(source: str) -> bool:
    """True when a module both parses JSON and touches log messages (the rule above)."""
    tree = ast.parse(source)
    modules: dict[str, str] = {}  # local name -> json / orjson
    parser_names: set[str] = set()  # a ``loads`` imported by name
    parses = touches = False
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                if a.name in ("json", "orjson"):
                    modules[a.asname or a.name] = a.name
        elif isinstance(node, ast.ImportFrom):
            mod = node.module or ""
            for a in node.names:
                if (mod, a.name) in PARSERS:
                    parser_names.add(a.asname or a.name)
                if a.name in MESSAGE_READERS and (mod.startswith("lfdfuse.log") or mod.startswith("mcap")):
                    touches = True
        elif isinstance(node, ast.Call):
            f = node.func
            if isinstance(f, ast.Attribute) and isinstance(f.value, ast.Name):
                parses |= (modules.get(f.value.id), f.attr) in PARSERS
            elif isinstance(f, ast.Name):
                parses |= f.id in parser_names
        elif isinstance(node, ast.Constant) and isinstance(node.value, str):
            touches |= node.value.startswith("/lfd/")
    return parses and touches


def offenders() -> set[str]:
    out = set()
    for path in sorted(PACKAGE.rglob("*.py")):
        if LOG in path.parents:
            continue
        if offends(path.read_text()):
            out.add(str(path.relative_to(ROOT)))
    return out


def test_no_module_outside_log_parses_log_messages() -> None:
    assert offenders() - PENDING == set()


def test_the_rule_sees_each_way_of_parsing_and_of_touching_messages() -> None:
    reads = "from lfdfuse.log.reader import iter_messages\n"
    assert offends(reads + "import orjson\nx = [orjson.loads(d) for *_, d in iter_messages(p)]\n")
    assert offends(reads + "import json as j\nj.loads(b)\n")
    assert offends("from orjson import loads\nloads(b)\ntopic = '/lfd/step'\n")
    assert offends("from mcap.reader import make_reader\nimport json\njson.load(f)\n")
    # JSON that is not a message, or messages read through their decoders: allowed
    assert not offends("import json\nmsg = json.loads(payload)  # a client's Twist\n")
    assert not offends(reads + "from lfdfuse.log import lfd\nlfd.NetworkStep.decode(data)\n'/lfd/step'\n")
    assert not offends("import orjson\norjson.dumps({'/lfd/x': 1})\n")
