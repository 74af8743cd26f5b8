"""The chromosome types the GA loop knows (what a chromosome *is*, not how a preset searches)."""

from __future__ import annotations

from enum import IntEnum
from typing import NamedTuple


class Kind(IntEnum):
    """Integer tag of a chromosome type; :mod:`subtask_opt.ga.dispatch` maps it to operators."""

    PERMUTATION = 0
    """A closed tour: a permutation of 0..N-1 (:mod:`subtask_opt.tour.permutation`)."""
    CONFIGURED_PERMUTATION = 1
    """A tour whose per-subtask configurations are decoded exactly
    (registered by :mod:`subtask_opt.tour.clustered`)."""
    WAYPOINT_PATH = 2
    """A variable-length list of grid waypoints
    (registered by :mod:`subtask_opt.planners.grid._waypoint_kernels`)."""
    PINNED_PERMUTATION = 3
    """A closed tour with a pinned first (and maybe last) node and precedence pairs
    (:mod:`subtask_opt.tour.precedence`)."""
    PINNED_CLUSTERED = 4
    """A pinned permutation of clusters whose nodes are decoded exactly (precedence with
    configurations: :mod:`subtask_opt.tour.pinned_clustered`)."""


# Numba sees a kind through the *type* of a tag argument: a distinct NamedTuple
# class per kind, so each kind gets its own compiled loop (holding only its
# operators) while Python calls still hit numba's fast typed dispatch.
class PermutationTag(NamedTuple):
    kind: int = Kind.PERMUTATION


class ConfiguredPermutationTag(NamedTuple):
    kind: int = Kind.CONFIGURED_PERMUTATION


class WaypointPathTag(NamedTuple):
    kind: int = Kind.WAYPOINT_PATH


class PinnedPermutationTag(NamedTuple):
    kind: int = Kind.PINNED_PERMUTATION


class PinnedClusteredTag(NamedTuple):
    kind: int = Kind.PINNED_CLUSTERED


TAGS: dict[Kind, type] = {Kind.PERMUTATION: PermutationTag,
                          Kind.CONFIGURED_PERMUTATION: ConfiguredPermutationTag,
                          Kind.WAYPOINT_PATH: WaypointPathTag,
                          Kind.PINNED_PERMUTATION: PinnedPermutationTag,
                          Kind.PINNED_CLUSTERED: PinnedClusteredTag}


def tag(kind: Kind) -> tuple[int]:
    """The tag value to pass to the loop kernel for ``kind``."""
    return TAGS[kind]()  # type: ignore[no-any-return]
