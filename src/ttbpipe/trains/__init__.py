"""Train library (axle positions and static loads by name) and moving-load runs by train name.

``get_train("HSLM-A1")``: the universal trains of EN 1991-2:2003 Annex E (``hslm.yaml``) and
real high-speed trains (``real_trains.yaml``: ICE2, Talgo350, AVE-S103-8, AVE-S103-16), each
with its source; docs/trains.md. A structure case selects a train for its moving
loads with ``loads.axle_train.train: NAME`` (``ttbpipe.structure.moving_loads.build_loads``).
"""

from .library import (Train, axle_table, car_train_axles, get_train, hslm_a_axles, library_table,
                      train_names)

__all__ = ["Train", "axle_table", "car_train_axles", "get_train", "hslm_a_axles",
           "library_table", "train_names"]
