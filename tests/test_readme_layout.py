"""The README's code-layout table matches the tree: every package and top-level module of
``flexnet_fe`` is listed, and every listed path exists."""

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_readme_code_layout_matches_tree():
    text = (ROOT / "README.md").read_text()
    section = text.split("## Code layout", 1)[1].split("\n## ", 1)[0]
    listed = set(re.findall(r"`(flexnet_fe/[\w/.]+)`", section))
    pkg = ROOT / "flexnet_fe"
    tree = {f"flexnet_fe/{p.name}/" for p in pkg.iterdir() if p.is_dir() and (p / "__init__.py").is_file()}
    tree |= {f"flexnet_fe/{p.name}" for p in pkg.glob("*.py") if p.name != "__init__.py"}
    assert not tree - listed, f"not in the README's code layout: {sorted(tree - listed)}"
    missing = {p for p in listed if not (ROOT / p).exists()}
    assert not missing, f"listed in the README but not in the tree: {sorted(missing)}"
