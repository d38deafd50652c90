"""The CMP facade labels (Tylecek & Sara 2013) the learned parser predicts, and their citygen layout labels."""
from __future__ import annotations

#: CMP label ids 1..12 in order (index = id - 1).
CMP_LABELS = ("background", "facade", "window", "door", "cornice", "sill", "balcony", "blind", "deco", "molding",
              "pillar", "shop")
#: The FacadeLayout label of each CMP label (the facade itself is wall; background is outside the facade).
LAYOUT_LABEL = {"background": "wall", "facade": "wall", "window": "window", "door": "door", "cornice": "cornice",
                "sill": "sill", "balcony": "balcony", "blind": "blind", "deco": "deco", "molding": "molding",
                "pillar": "pillar", "shop": "shop"}
#: Label-map colours (RGB) for ``citygen layout from-photo --labels``.
COLOURS = ((0, 0, 0), (222, 205, 170), (70, 110, 160), (120, 70, 40), (250, 250, 245), (240, 240, 235),
           (90, 90, 100), (60, 120, 70), (230, 220, 200), (245, 240, 225), (190, 180, 160), (40, 70, 110))
