"""The thesis' kind of maps: six 14 x 9 workspaces of rising difficulty, a trap,
and the thesis' one surviving map, Fig. 2.4.

The thesis' own maps are figures that did not survive, so these are rebuilt
to the same recipe: 14 x 9 cells of 3 cm (42 cm x 27 cm), the border treated
as obstacle (so the planners see a 16 x 11 array), start on the left and goal
on the right, the last map as cluttered as its Fig. 4.6. ``S`` and ``G`` in
the drawings mark start and goal.

``fig2.4`` is the worked distance-transform example of the thesis (14 x 9
work space, obstacles rows 1-3 cols 1-4 and rows 5-8 cols 9-13, S (2, 7),
G (12, 1)). It comes without the border, so that its cells are the printed
work-space coordinates; cells outside a grid count as blocked for every
planner, so the border changes no distance.

:func:`thesis_case` returns the world and the start and goal in its
coordinates (bordered maps: drawing coordinates + 1; :attr:`GridCase.border`
says how many cells were added on each side).
"""

from __future__ import annotations

from dataclasses import dataclass

from subtask_opt.base.errors import ParameterError
from subtask_opt.planners.grid.world import GridWorld

#: Cell side of the thesis' workspace, in metres.
THESIS_CELL_SIZE = 0.03

_DRAWINGS: dict[str, str] = {
    "open": """
        ..............
        ..............
        .....##.....G.
        .....##.......
        .....##.......
        .....##.......
        ..S..##.......
        ..............
        ..............
    """,
    "walls": """
        ..............
        ....#.........
        ....#.....#...
        ....#.....#.G.
        .S..#.....#...
        ....#.....#...
        ..........#...
        ..........#...
        ..............
    """,
    "blocks": """
        ..............
        .S....#.......
        ......#..###..
        ..##..#....#..
        ..##..#....#..
        ......####.#..
        ...........#G.
        .#######...#..
        ..............
    """,
    "rooms": """
        ......#.......
        .S....#...#...
        ......#...#...
        ###.###...#...
        ......#...###.
        ......#.......
        ..#####..###..
        ..........#.G.
        ..........#...
    """,
    "spiral": """
        ..............
        .##########...
        .#........#...
        .#.S......#...
        .#........#.G.
        .#.########...
        .#............
        .#####.######.
        ..............
    """,
    "cluttered": """
        ..#....#....#.
        S.#.##.#.##.#.
        ..#..#...#....
        .##..#.###..#.
        .....#...#.##.
        .####.##.#....
        .#.....#...##.
        .#.###.#.#..#G
        ...#.....#....
    """,
    # a U-shaped bay opening towards the start, the goal behind it: local
    # planners that follow the target's pull drive into the bay and stall
    "trap": """
        ..............
        ..............
        .......####...
        ..........#...
        .S........#.G.
        ..........#...
        .......####...
        ..............
        ..............
    """,
    # the thesis' Fig. 2.4 (printed field: tests/planners/grid/test_fig24.py)
    "fig2.4": """
        ..............
        .####.......G.
        .####.........
        .####.........
        ..............
        .........#####
        .........#####
        ..S......#####
        .........#####
    """,
}

#: The six comparison maps, easiest first.
THESIS_MAPS: tuple[str, ...] = ("open", "walls", "blocks", "rooms", "spiral", "cluttered")
#: Every named map (the six, ``"trap"`` and the thesis' ``"fig2.4"``).
MAP_NAMES: tuple[str, ...] = (*THESIS_MAPS, "trap", "fig2.4")
#: Maps that come without the border by default (their printed coordinates).
UNBORDERED: frozenset[str] = frozenset({"fig2.4"})


@dataclass(frozen=True)
class GridCase:
    """A world with its start and goal cells (x, y), and the blocked border
    (cells per side) added around the drawn work space."""

    world: GridWorld
    start: tuple[int, int]
    goal: tuple[int, int]
    border: int = 0

    @property
    def name(self) -> str:
        return self.world.name


def _find(rows: list[str], char: str) -> tuple[int, int]:
    for y, row in enumerate(rows):
        if char in row:
            return row.index(char), y
    raise AssertionError(f"marker {char!r} missing from a built-in map")  # pragma: no cover


def thesis_case(name: str, *, border: bool | None = None) -> GridCase:
    """The named map with its start and goal.

    Args:
        name: one of :data:`MAP_NAMES`.
        border: add the thesis' blocked border (16 x 11 array); start and goal
            shift by one cell accordingly. ``None``: yes, except for the maps
            of :data:`UNBORDERED`.

    Raises:
        ParameterError: unknown ``name``.
    """
    if name not in _DRAWINGS:
        raise ParameterError(f"unknown map {name!r}; built-in maps: {', '.join(MAP_NAMES)}")
    rows = [ln.strip() for ln in _DRAWINGS[name].strip().splitlines()]
    world = GridWorld.from_ascii("\n".join(rows), cell_size=THESIS_CELL_SIZE, name=name)
    start, goal = _find(rows, "S"), _find(rows, "G")
    if border is None:
        border = name not in UNBORDERED
    if border:
        world = world.with_border()
        start, goal = (start[0] + 1, start[1] + 1), (goal[0] + 1, goal[1] + 1)
    return GridCase(world, start, goal, int(border))


def thesis_map(name: str, *, border: bool | None = None) -> GridWorld:
    """The named map alone (see :func:`thesis_case`)."""
    return thesis_case(name, border=border).world
