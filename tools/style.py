"""Drawing conventions shared by the rerun recording and the pictures (RGB, 0-255).

Cells: tiles sand, obstacles dark grey, empty cells off-white. Goal marks: a green frame on a
cell that must gain a tile, a purple one on a tile that must go. Robots: a line from the back foot
to the front foot (so the heading shows), a large disc on the front foot, a small one on the back
foot, the carried tile a small sand square with the robot's color around it, the robot's goal
cell a ring of its color; the collision set of the step just made is shaded in its color. A rule
violation is red.
"""
from __future__ import annotations

import string

import numpy as np

EMPTY = (250, 250, 246)
TILE = (214, 178, 112)
OBSTACLE = (60, 60, 60)
GOAL_FILL = (30, 150, 60)
GOAL_CLEAR = (150, 70, 170)
VIOLATION = (230, 20, 20)
#: Robot colors, far from the cell and goal colors above; robot ``i`` takes ``ROBOTS[i % 10]``.
ROBOTS = ((31, 119, 180), (255, 127, 14), (23, 190, 207), (227, 119, 194), (140, 86, 75),
          (57, 59, 121), (188, 189, 34), (127, 127, 127), (0, 128, 128), (107, 174, 214))

FRONT_RADIUS, BACK_RADIUS, GOAL_RADIUS = 0.32, 0.2, 0.4


def robot_color(i: int) -> tuple[int, int, int]:
    return ROBOTS[i % len(ROBOTS)]


def robot_name(i: int) -> str:
    """``A`` .. ``Z``, then ``R26``, ``R27``, ... (the letters of ``bille show``)."""
    return string.ascii_uppercase[i] if i < 26 else f"R{i}"


#: Cell classes of the structure image: (class id, label, color).
CELL_CLASSES = ((0, "empty", EMPTY), (1, "tile", TILE), (2, "obstacle", OBSTACLE))


def cell_classes(tiles: np.ndarray, obstacles: np.ndarray, width: int, height: int) -> np.ndarray:
    """``uint8[H, W]``: class id of every cell (0 empty, 1 tile, 2 obstacle)."""
    ids = tiles.astype(np.uint8)
    ids[obstacles] = 2
    return ids.reshape(height, width)


def cell_image(tiles: np.ndarray, obstacles: np.ndarray, width: int, height: int) -> np.ndarray:
    """``uint8[H, W, 3]``: the grid's cells in their colors, one pixel per cell."""
    img = np.empty((width * height, 3), dtype=np.uint8)
    img[:] = EMPTY
    img[tiles] = TILE
    img[obstacles] = OBSTACLE
    return img.reshape(height, width, 3)
