"""Sphinx configuration of the API reference, built from the package's docstrings (numpy style).

Build it (CI runs the same with ``-W --keep-going -n -q``: every warning fails, every cross-reference must
resolve)::

    sphinx-build -W --keep-going -n -b html docs/api docs/api/_build

Each object is documented once, in the module that defines it. A cross-reference may name it by any path the
package really exposes it under (``frenbrdf.NBRDF``, ``frenbrdf.models.NBRDF``, or a name the docstring's own
module imported): :func:`_resolve_alias` follows that path to the object and links to where it is documented.
"""

from __future__ import annotations

import importlib
import inspect
import pkgutil
import re
from pathlib import Path

from sphinx.util import logging

import frenbrdf

project = "FreNBRDF"
author = "FreNBRDF contributors"
copyright = "FreNBRDF contributors"
release = frenbrdf.__version__
version = release

extensions = ["sphinx.ext.autodoc", "sphinx.ext.autosummary", "sphinx.ext.napoleon"]
# No intersphinx: the build must not fetch inventories (CI reaches package registries only).

exclude_patterns = ["_build"]
html_theme = "furo"
html_title = f"frenbrdf {release} API reference"

# Every object in the module that defines it (``ignore-module-all``: a package's ``__all__`` re-exports are
# listed in a summary table on its page, not documented a second time), in source order.
autodoc_default_options = {
    "members": True,
    "ignore-module-all": True,
    "member-order": "bysource",
    "special-members": "__call__",
}
autodoc_inherit_docstrings = False  # torch's own docstrings (Module.forward) are not this package's
autosummary_generate = False  # summary tables only (``frenbrdf``'s face, a package's ``__all__``): no stub pages

napoleon_google_docstring = False
napoleon_numpy_docstring = True
napoleon_preprocess_types = True  # "int, optional" in a Parameters entry: a link and a word, not a broken link
napoleon_use_rtype = False
# Not the annotations as the types of an Attributes section: napoleon writes ``frozenset[str]`` as one class name.
# A dataclass's signature shows them.
napoleon_attr_annotations = False

add_module_names = False

# Types of libraries without an inventory here (no intersphinx): their names stay plain text, not links.
nitpick_ignore_regex = [
    (r"py:.*", r"(np|numpy|torch|scipy|h5py|matplotlib|mitsuba|mi|drjit|dr|tqdm)(\..*)?"),  # third-party
    (r"py:.*", r"(os|pathlib|collections\.abc|typing|dataclasses|argparse|json|concurrent\.futures)\..*"),  # stdlib
    (r"py:class", r"(Path|PathLike|Callable|Iterable|Iterator|Sequence|Mapping)"),  # stdlib, as annotated
    # Private names in public signatures: the Rust core's classes, helpers such as models.editing._Ends.
    (r"py:class", r"frenbrdf\.(.+\.)?_\w+(\..*)?"),
]


_MISSING = object()


def _named(path: str):
    """The object ``path`` (dotted) names, importing its longest module prefix; ``_MISSING`` when it names none.

    Attributes of a class are read without the descriptor protocol, so a classmethod is the same object each time.
    """
    parts = path.split(".")
    for split in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:split]))
        except ImportError:
            continue
        for name in parts[split:]:
            try:
                obj = inspect.getattr_static(obj, name) if inspect.isclass(obj) else getattr(obj, name)
            except AttributeError:
                return _MISSING
        return obj
    return _MISSING


def _identifiable(obj) -> bool:
    """Whether ``obj`` being the same object under two names means that one name re-exports the other: not for
    the values Python shares between unrelated names (None, booleans, small integers, strings)."""
    if obj is _MISSING or obj is None or isinstance(obj, (bool, str, bytes)):
        return False
    return not (type(obj) is int and -5 <= obj <= 256)


class _Documented:
    """The objects of the Python domain, read once in the writing phase (when every page has been read)."""

    def __init__(self, env):
        self.by_id: dict[int, str] = {}  # id(object) → the full name it is documented under
        self.by_name: dict[str, list[str]] = {}  # last component → full names
        self.objects = []  # kept, so that no id is reused
        for name in env.get_domain("py").objects:
            self.by_name.setdefault(name.rpartition(".")[2], []).append(name)
            obj = _named(name)
            if _identifiable(obj):
                self.by_id.setdefault(id(obj), name)
                self.objects.append(obj)

    def of(self, obj, name: str) -> str | None:
        """Where ``obj``, met under a name ending in ``name``, is documented: the same object, or else the one
        documented object of that name and an equal value (a constant re-exported: a string is no one object)."""
        if _identifiable(obj) and id(obj) in self.by_id:
            return self.by_id[id(obj)]
        same = [full for full in self.by_name.get(name, []) if _equal(_named(full), obj)]
        return same[0] if len(same) == 1 else None


def _equal(a, b) -> bool:
    try:
        return type(a) is type(b) and bool(a == b)
    except Exception:  # an array compares element-wise
        return False


_DOCUMENTED: list[_Documented] = []


def _resolve_alias(app, env, node, contnode):
    """A reference to an object of the package that is documented under another path, linked there.

    The target is looked up as the Python domain looks it up (in the class, in the module, as written) but in the
    package itself, so ``frenbrdf.NBRDF``, ``frenbrdf.models.NBRDF`` and a name the docstring's module imported
    all reach the one documentation of the object. Failing that, a target that one documented name ends with
    (a docstring's name shown out of its module, as in a summary table) links there.
    """
    if node.get("refdomain") != "py":
        return None
    if not _DOCUMENTED:
        _DOCUMENTED.append(_Documented(env))
    documented, domain = _DOCUMENTED[0], env.get_domain("py")
    target, kind = node["reftarget"].lstrip(".~"), node["reftype"]
    module, cls = node.get("py:module"), node.get("py:class")
    candidates = ([f"{module}.{cls}.{target}"] if module and cls else []) + ([f"{module}.{target}"] if module else [])
    for path in [*candidates, target]:
        if path == "frenbrdf" or path.startswith("frenbrdf."):
            owner, _, name = path.rpartition(".")
            obj = _named(path)
            full = None if obj is _MISSING else documented.of(obj, name)
            if obj is _MISSING and inspect.isclass(found := _named(owner)):  # an instance attribute (``self.x``)
                where = documented.of(found, owner.rpartition(".")[2])
                full = None if where is None else f"{where}.{name}"
            if full is not None and full in domain.objects:
                return domain.resolve_xref(env, node["refdoc"], app.builder, kind, full, node, contnode)
    if kind in {"meth", "attr"} and "." not in target:
        return None  # a bare method or attribute name belongs to its class
    ends = [full for full in domain.objects if full.endswith(f".{target}")]
    if len(ends) == 1:
        return domain.resolve_xref(env, node["refdoc"], app.builder, kind, ends[0], node, contnode)
    return None


def _check_summaries(app):
    """Warns where a page's summary tables (``.. autosummary::`` after ``.. currentmodule:: M``) and ``M.__all__``
    differ, so that a name added to or removed from a package's face shows up here."""
    log = logging.getLogger(__name__)
    for page in sorted(Path(app.srcdir).glob("*.rst")):
        listed: dict[str, set[str]] = {}
        module, in_summary = None, False
        for line in page.read_text(encoding="utf-8").splitlines():
            if line.startswith(".. currentmodule:: "):
                module = line.split("::", 1)[1].strip()
            elif line.startswith(".. autosummary::"):
                in_summary = True
            elif in_summary and line.startswith("   ") and not line.lstrip().startswith(":"):
                listed.setdefault(module, set()).add(line.strip())
            elif line and not line.startswith(" "):
                in_summary = False
        for module, names in listed.items():
            public = {name for name in importlib.import_module(module).__all__ if not name.startswith("_")}
            for name in sorted(public - names):
                log.warning("%s.__all__ has %r, which %s does not list", module, name, page.name)
            for name in sorted(names - public):
                log.warning("%s lists %r, which is not in %s.__all__", page.name, name, module)


_SUBMODULES = re.compile(r"^\.\. submodules:: (\S+)(?: except (.+))?$", flags=re.MULTILINE)


def _submodules(app, docname, source):
    """``.. submodules:: PACKAGE [except NAME ...]`` in a page: a section with the ``automodule`` of each public
    module of the package, in alphabetical order, so that a module added, moved or removed needs no page edit."""

    def sections(match: re.Match) -> str:
        package, skipped = match[1], set((match[2] or "").split())
        names = sorted(info.name for info in pkgutil.iter_modules(importlib.import_module(package).__path__)
                       if not info.name.startswith("_") and info.name not in skipped)
        return "\n".join(f"``{package}.{name}``\n{'-' * (len(package) + len(name) + 5)}\n\n"
                         f".. automodule:: {package}.{name}\n" for name in names)

    source[0] = _SUBMODULES.sub(sections, source[0])


def _prose_attributes(app, what, name, obj, options, lines):
    """Napoleon reads the first line ``X: Y`` of an attribute's docstring as its type X. Here they are prose
    ("The largest render (pixels per side): ..."): an empty comment first keeps that line as it is written."""
    if what in {"attribute", "data", "property"} and lines:
        lines[:0] = ["..", ""]


def _factory_defaults(app, what, name, obj, options, signature, return_annotation):
    """A dataclass field's ``default_factory`` shows as ``<factory>``, which makes the signature unparsable (it is
    then split at every comma, ``dict[str, float]`` too): written ``...`` instead."""
    if signature and "<factory>" in signature:
        return signature.replace("<factory>", "..."), return_annotation
    return None


def setup(app):
    app.connect("builder-inited", _check_summaries)
    app.connect("source-read", _submodules)
    app.connect("autodoc-process-docstring", _prose_attributes, priority=400)  # before napoleon's (500)
    app.connect("autodoc-process-signature", _factory_defaults)
    app.connect("missing-reference", _resolve_alias)
