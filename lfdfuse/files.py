"""Files at the edge: atomic output (temp file, fsync, rename) and the YAML files users hand us.

An interrupted or failed command leaves no half-written output behind; a YAML syntax error
names the file and line.
"""

from __future__ import annotations

import errno
import os
import secrets
import stat
from enum import Enum
from pathlib import Path
from typing import Any

import yaml

from lfdfuse.errors import ConfigError, LfdError


def umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def write_text_atomic(path: str | Path, text: str) -> None:
    """Write ``text`` to ``path`` atomically, with the usual permissions; errors as :class:`LfdError`."""
    write_bytes_atomic(path, text.encode())


#: names drawn for a temp file before giving up (8 random hex digits: a clash is a stale file)
TEMP_TRIES = 100


class TempBeside:
    """The temp file an output is written to before its rename, in the output's folder
    (``.NAME.XXXXXXXX.tmp``).

    Its name is known before the file exists (``tempfile.mkstemp`` returns it only once the file
    is made), so :meth:`remove` finds it whatever interrupts its making: a SIGTERM as the command
    starts, raised between two lines, leaves nothing behind.
    """

    def __init__(self, path: Path) -> None:
        self.folder = path.parent if str(path.parent) else Path(".")
        self.prefix = f".{path.name}."
        self.name = ""

    def open(self) -> int:
        """Create the file, only this process's (mode 0600 until renamed); its descriptor."""
        flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL  # as mkstemp opens it
        for extra in ("O_NOFOLLOW", "O_BINARY", "O_CLOEXEC"):
            flags |= getattr(os, extra, 0)
        for _ in range(TEMP_TRIES):
            self.name = str(self.folder / f"{self.prefix}{secrets.token_hex(4)}.tmp")
            try:
                return os.open(self.name, flags, 0o600)
            except FileExistsError:
                self.name = ""  # another's: never removed as ours
        raise FileExistsError(errno.EEXIST, "no free temp file name")

    def remove(self) -> None:
        if self.name and os.path.exists(self.name):
            os.unlink(self.name)


def write_bytes_atomic(path: str | Path, data: bytes) -> None:
    """Write ``data`` to ``path`` atomically (temp file in the folder, fsync, rename)."""
    p = Path(path)
    parent = p.parent if str(p.parent) else Path(".")
    if not parent.is_dir():
        raise LfdError(f"cannot write {p}: folder {parent} does not exist")
    tmp = TempBeside(p)
    try:
        with os.fdopen(tmp.open(), "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.chmod(tmp.name, 0o666 & ~umask())
        os.replace(tmp.name, p)
    except OSError as exc:
        raise LfdError(f"cannot write {p}: {exc.strerror}") from exc
    finally:
        tmp.remove()


#: a YAML file we parse is at most this big (a world of ~100,000 points is ~3 MB; parsing
#: YAML runs at a few MB/s, so this also bounds the time)
MAX_CONFIG_BYTES = 4 * 2**20
#: deepest nesting of a YAML document (a world's walls are 4 deep, a table's nested networks ~3 per level)
MAX_YAML_DEPTH = 64
#: most nodes of a YAML document once its aliases are expanded (an anchor bomb is billions)
MAX_YAML_NODES = 1_000_000
#: longest integer literal read (a float holds at most 309 digits; Python refuses to parse past 4300)
MAX_INT_CHARS = 400

_STR_TAG = "tag:yaml.org,2002:str"
_INT_TAG = "tag:yaml.org,2002:int"
_MERGE_TAG = "tag:yaml.org,2002:merge"


# libyaml's parser is ~20x faster than PyYAML's and refuses nesting past 1000 levels itself
_Loader: Any = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


def _line(node: yaml.Node) -> str:
    return f" at line {node.start_mark.line + 1}" if node.start_mark is not None else ""


def _check_scalar(node: yaml.Node, origin: str, error: type[LfdError]) -> None:
    if node.tag == _INT_TAG and len(node.value) > MAX_INT_CHARS:
        raise error(f"{origin}: an integer of {len(node.value)} digits{_line(node)} (too large for a number)")


def _check_keys(node: yaml.MappingNode, origin: str, error: type[LfdError]) -> None:
    """Mapping keys are strings (a merge ``<<`` aside): every reader sorts and names them."""
    for key, _value in node.value:
        if key.tag == _MERGE_TAG:
            continue
        if not isinstance(key, yaml.ScalarNode) or key.tag != _STR_TAG:
            text = key.value if isinstance(key, yaml.ScalarNode) else f"a {key.id}"
            shown = text if len(text) <= 40 else text[:37] + "..."
            raise error(f"{origin}: mapping key {shown!r}{_line(key)} must be a name (a string)")


def _measure(root: yaml.Node, origin: str, error: type[LfdError]) -> None:
    """Refuse documents nested too deep or too big once aliases are expanded (an anchor bomb),
    walking the composed node graph iteratively with each shared (aliased) node sized once;
    on the way, refuse mapping keys that are not strings and integers too long for a number."""
    size: dict[int, int] = {}
    stack: list[tuple[yaml.Node, int, bool]] = [(root, 1, False)]
    while stack:
        node, depth, done = stack.pop()
        if depth > MAX_YAML_DEPTH:
            raise error(f"{origin}: YAML nested deeper than {MAX_YAML_DEPTH} levels")
        if isinstance(node, yaml.SequenceNode):
            children = list(node.value)
        elif isinstance(node, yaml.MappingNode):
            if not done:
                _check_keys(node, origin, error)
            children = [c for kv in node.value for c in kv]
        else:
            _check_scalar(node, origin, error)
            size[id(node)] = 1
            continue
        if done:
            size[id(node)] = min(1 + sum(size[id(c)] for c in children), MAX_YAML_NODES + 1)
            continue
        if id(node) in size:
            continue
        size[id(node)] = 0  # in progress: a recursive alias counts as nothing more
        stack.append((node, depth, True))
        for c in children:
            if size.get(id(c)) == 0:  # an alias to a node still being walked: its own ancestor
                raise error(f"{origin}: a YAML alias refers to itself (a recursive document)")
            if id(c) not in size:
                stack.append((c, depth + 1, False))
    if size[id(root)] > MAX_YAML_NODES:
        raise error(f"{origin}: too many YAML nodes once aliases are expanded (an anchor bomb?)")


def parse_yaml(text: str, *, origin: str, error: type[LfdError] = ConfigError) -> Any:
    """YAML text into data, within size, depth and alias-expansion limits; errors name the file and line."""
    if len(text) > MAX_CONFIG_BYTES:
        raise error(f"{origin}: larger than {MAX_CONFIG_BYTES // 2**20} MB")
    loader = None
    try:
        loader = _Loader(text)
        root = loader.get_single_node()
        if root is None:
            return None
        _measure(root, origin, error)
        return loader.construct_document(root)
    except RecursionError:
        raise error(f"{origin}: YAML nested too deeply") from None
    except (ValueError, OverflowError) as exc:  # a scalar its constructor refuses (a date 2001-13-45)
        raise error(f"{origin}: malformed YAML value ({str(exc).splitlines()[0][:100]})") from exc
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" at line {mark.line + 1}" if mark is not None else ""
        problem = getattr(exc, "problem", None) or getattr(exc, "reason", None)
        raise error(f"{origin}: malformed YAML{where}" + (f" ({problem})" if problem else "")) from exc
    finally:
        if loader is not None:
            loader.dispose()


def read_text(path: str | Path, *, what: str, error: type[LfdError] = ConfigError) -> str:
    """A user's text file, refused before reading when it is not a regular file or too big."""
    p = Path(path)
    try:
        st = p.stat()
    except OSError as exc:
        raise error(f"cannot read {what} {p}: {exc.strerror}") from exc
    if not stat.S_ISREG(st.st_mode):
        raise error(f"cannot read {what} {p}: not a regular file")
    if st.st_size > MAX_CONFIG_BYTES:
        raise error(f"{what} {p} is larger than {MAX_CONFIG_BYTES // 2**20} MB")
    try:
        data = p.read_bytes()
    except OSError as exc:
        raise error(f"cannot read {what} {p}: {exc.strerror}") from exc
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise error(f"{what} {p} is not a text file (not UTF-8 at byte {exc.start})") from None


def read_yaml(path: str | Path, *, what: str, error: type[LfdError] = ConfigError) -> Any:
    """Read and parse a YAML file; ``what`` names it in errors ("task file", "fusion table")."""
    return parse_yaml(read_text(path, what=what, error=error), origin=str(path), error=error)


class YamlKind(Enum):
    """Which of lfdfuse's YAML files a document is, told by its top level."""

    #: a fusion table: a mapping with ``format:`` (``lfdfuse/fusion-table@1``)
    TABLE = "fusion table"
    #: a task: a mapping with ``task:`` (a list of ``{target, style}`` legs)
    TASK = "task"
    #: a world: any other mapping (``walls``, ``obstacles``, ``targets``, ``start``…)
    WORLD = "world"


def kind_of(data: object) -> YamlKind | None:
    """The kind of a parsed YAML document, or None when it is not a mapping (none of ours).

    Only the top-level keys are looked at; the kind's own loader checks the rest.

    >>> kind_of({"format": "lfdfuse/fusion-table@1", "behaviors": []})
    <YamlKind.TABLE: 'fusion table'>
    >>> kind_of({"task": [{"target": "red", "style": "keep-left"}]})
    <YamlKind.TASK: 'task'>
    >>> kind_of({"walls": []}), kind_of({}), kind_of([1, 2]), kind_of(None)
    (<YamlKind.WORLD: 'world'>, <YamlKind.WORLD: 'world'>, None, None)
    """
    if not isinstance(data, dict):
        return None
    if "format" in data:
        return YamlKind.TABLE
    if "task" in data:
        return YamlKind.TASK
    return YamlKind.WORLD
