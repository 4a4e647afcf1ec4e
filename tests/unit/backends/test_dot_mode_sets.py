"""The DOT backend's compact wording of mode sets."""

from __future__ import annotations


def test_compact_mode_sets() -> None:
    from afsmc.check.modegraph import compact

    assert compact(list(range(16))) == "{0..15}"
    assert compact([*range(1, 12), 14, 15]) == "{1..11, 14, 15}"
    assert compact([3, 1]) == "{1, 3}"
