"""The documentation stays in step with the code."""

from pathlib import Path

from footfall.features.pose_features import POSE_FEATURE_NAMES
from footfall.features.terrain_features import QUANTITIES

DOCS = Path(__file__).resolve().parent.parent / "docs"


def test_feature_docs_name_every_feature():
    text = (DOCS / "features.md").read_text()
    for name in POSE_FEATURE_NAMES:
        assert f"`{name}`" in text, name
    for q in QUANTITIES:
        assert f"SCALE.{q}" in text, q


def test_module_previews_exist():
    assert (DOCS / "modules.png").read_bytes()[:4] == b"\x89PNG"
