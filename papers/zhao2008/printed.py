"""The equations as printed: LaTeX blocks of the seed text, grouped by equation number.

``extract`` reads the paper's text (the seed file, Markdown with $$...$$ blocks) and
returns {"(N)": "LaTeX"} for N = 1..44, joining the sub-equations (Na), (Nb), ... and the
unnumbered blocks that continue a numbered one.  The result is stored in
``printed.json`` so the reproduction runs without the seed beside the repository.
"""

from __future__ import annotations

import json
import pathlib
import re

HERE = pathlib.Path(__file__).resolve().parent
SEED = HERE.parents[2] / "shared" / "seed" / "000_b31e6edea8a5809c.txt"
CACHE = HERE / "printed.json"

_BLOCK = re.compile(r"\$\$(.*?)\$\$", re.S)
_LABEL = re.compile(r"\\quad\s*\((\d+)([a-c]?)\)")
# unnumbered blocks that belong to a numbered equation: (blocks before, blocks after)
_AROUND = {"(16)": (0, 1), "(41)": (0, 3), "(42)": (0, 3), "(43)": (1, 1)}


def extract(text: str) -> dict[str, str]:
    blocks = [b.strip() for b in _BLOCK.findall(text)]
    out: dict[str, list[str]] = {}
    for i, body in enumerate(blocks):
        m = _LABEL.search(body)
        if not m:
            continue
        key = f"({m.group(1)})"
        before, after = _AROUND.get(key, (0, 0)) if m.group(2) in ("", "a") else (0, 0)
        rows = [blocks[j] for j in range(max(0, i - before), i) if not _LABEL.search(blocks[j])]
        rows.append(_LABEL.sub("", body).strip())
        rows += [blocks[j] for j in range(i + 1, min(len(blocks), i + 1 + after))
                 if not _LABEL.search(blocks[j])]
        out.setdefault(key, []).extend(rows)
    return {k: r" \\ ".join(v) for k, v in out.items()}


def load() -> dict[str, str]:
    """Printed LaTeX by label: from the seed when it is beside the repo, else the cache."""
    if SEED.exists():
        return extract(SEED.read_text(encoding="utf-8"))
    return json.loads(CACHE.read_text(encoding="utf-8"))


if __name__ == "__main__":
    data = extract(SEED.read_text(encoding="utf-8"))
    CACHE.write_text(json.dumps(data, indent=1, ensure_ascii=False) + "\n", encoding="utf-8")
    missing = [f"({n})" for n in range(1, 45) if f"({n})" not in data]
    print(f"{len(data)} equations written to {CACHE}; missing: {missing}")
