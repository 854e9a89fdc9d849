"""MkDocs hooks of the site (mkdocs.yml).

* The notebooks in notebooks/ become pages (tutorials/NAME.md): Markdown
  cells are copied, code cells become Python code blocks, and the notebook
  itself is published beside its page for download. The notebooks are stored
  without outputs; with ``MULTIARM_DOCS_EXECUTE=1`` the build runs each one
  (nbclient) and shows its outputs too: text, tables, Markdown and PNG
  figures (embedded).
* Mentions of SEEDS.md (the papers' mechanisms, kept beside the repository)
  link to the site's own restatement, papers.md.
* Sphinx roles in docstrings (``:func:`solve```) are shown as plain code in
  the API reference.
"""

from __future__ import annotations

import base64
import os
import posixpath
import re
from pathlib import Path
from typing import Any

import nbformat
from mkdocs.structure.files import File, Files

ROOT = Path(__file__).resolve().parents[2]
NOTEBOOKS = ROOT / "notebooks"


def _fence(text: str, lang: str = "") -> str:
    ticks = "```"
    while ticks in text:
        ticks += "`"
    return f"{ticks}{lang}\n{text.rstrip()}\n{ticks}\n"


def _output(out: Any) -> str:
    kind = out.get("output_type")
    if kind == "stream":
        return _fence(out.get("text", ""), "text")
    if kind == "error":
        return _fence("\n".join(out.get("traceback", [])), "text")
    data = out.get("data", {})
    if "image/png" in data:
        png = data["image/png"]
        if isinstance(png, bytes):
            png = base64.b64encode(png).decode()
        return f'<img alt="figure" src="data:image/png;base64,{png.strip()}">\n'
    if "text/markdown" in data:
        return str(data["text/markdown"]) + "\n"
    if "text/html" in data:
        return str(data["text/html"]) + "\n"
    if "text/plain" in data:
        return _fence(str(data["text/plain"]), "text")
    return ""


def render(path: Path, execute: bool = False) -> str:
    """The Markdown page of one notebook."""
    nb = nbformat.read(path, as_version=4)
    if execute:
        from nbclient import NotebookClient

        NotebookClient(
            nb,
            timeout=600,
            kernel_name="python3",
            resources={"metadata": {"path": str(path.parent)}},
        ).execute()
    parts = []
    for i, cell in enumerate(nb.cells):
        src = cell.source.rstrip()
        if cell.cell_type == "markdown":
            parts.append(src + "\n")
            if i == 0:
                parts.append(
                    f"*This page is the notebook `notebooks/{path.name}` "
                    f"([download]({path.name})); the test suite runs it. "
                    + (
                        "Outputs below are from the documentation build.*\n"
                        if execute
                        else "Run it in Jupyter to see its tables and figures.*\n"
                    )
                )
        elif cell.cell_type == "code":
            code = "\n".join(
                line for line in src.splitlines() if not line.startswith("%matplotlib")
            )
            parts.append(_fence(code, "python"))
            for out in cell.get("outputs", []):
                parts.append(_output(out))
    return "\n".join(parts)


def on_files(files: Files, config: Any) -> Files:
    """Add tutorials/NAME.md (and the notebook) for every notebooks/NAME.ipynb."""
    execute = os.environ.get("MULTIARM_DOCS_EXECUTE", "") not in ("", "0")
    for path in sorted(NOTEBOOKS.glob("*.ipynb")):
        files.append(
            File.generated(config, f"tutorials/{path.stem}.md", content=render(path, execute))
        )
        files.append(File.generated(config, f"tutorials/{path.name}", content=path.read_bytes()))
    return files


_SEEDS = re.compile(r"(?<![\w/.`\[])(?:\.\./shared/)?SEEDS\.md(?![\w`\]])")
_ROLE = re.compile(r":(?:class|func|meth|mod|attr|data|exc|obj|ref):(<code>)~?")


def on_page_markdown(markdown: str, page: Any, config: Any, files: Files) -> str:
    """Link mentions of SEEDS.md (outside code) to the site's papers page."""
    target = posixpath.relpath("papers.md", posixpath.dirname(page.file.src_uri) or ".")
    out, fence = [], False
    for line in markdown.split("\n"):
        if line.lstrip().startswith(("```", "~~~")):
            fence = not fence
        if not fence and page.file.src_uri != "papers.md":
            parts = line.split("`")
            # only the parts outside inline code spans (even indices)
            line = "`".join(
                _SEEDS.sub(f"[the papers]({target})", p) if i % 2 == 0 else p
                for i, p in enumerate(parts)
            )
        out.append(line)
    return "\n".join(out)


def on_page_content(html: str, page: Any, config: Any, files: Files) -> str:
    """Sphinx roles from the docstrings (``:func:`x```) as plain code."""
    return _ROLE.sub(r"\1", html)
