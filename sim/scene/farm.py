"""Farms: copies of a scene's device on a grid, as one scene of several bodies.

`[farm] rows, columns, spacing` turns a scene into rows x columns devices, 'd1', 'd2', ... row by row, each moved by
(column x spacing, row x spacing) in x and y from where the scene places it. The device is the scene's one body (its
[body], [initial] and [constraint] tables), named d1, d2, ...; or all its [[bodies]], each named dN_NAME, with their
joints to one another copied. Every device keeps its own joint and take-off, so the run's CSV has each one's power.

With `[fluid] radiation = "bem"` the devices are solved together (system.SystemRadiation): their radiated and scattered
waves act on one another (the farm's interactions). Capytaine's dense solve costs about 2 x 16 (N panels)^2 bytes and
grows as N^3 in time: `check_panels` refuses a farm whose solve would pass a share of the memory, before meshing
anything more. Mooring lines per device are not built (one line file cannot be copied): a farm with [moorings] is
refused.
"""

from __future__ import annotations

from dataclasses import replace

from sim.errors import ConfigError


def expand(scene, entry):
    """The scene with its [farm] laid out as [[bodies]] (unchanged when the farm is one device); `entry` makes a
    [[bodies]] entry (config.BodyEntry: config calls this module, not the other way)."""
    farm = scene.farm
    count = int(farm.rows) * int(farm.columns)
    if count <= 1:
        return scene
    if scene.moorings.lines or scene.moorings.anchors or scene.moorings.line_file:
        raise ConfigError("[farm] with [moorings]: each device's own lines are not built (a line file cannot be copied); take the "
                          "[moorings] table out, or run one device")  # fmt: skip
    if scene.bodies:
        device, single = scene.bodies, False
    else:
        device, single = (entry("body", "world", scene.body, scene.initial, scene.constraint),), True
    _check_apart(device, farm)
    entries = []
    for row in range(int(farm.rows)):
        for column in range(int(farm.columns)):
            n = row * int(farm.columns) + column + 1
            shift = (column * farm.spacing, row * farm.spacing, 0.0)
            for e in device:
                name = f"d{n}" if single else f"d{n}_{e.name}"
                parent = e.parent if e.parent == "world" else f"d{n}_{e.parent}"
                position = tuple(float(p) + s for p, s in zip(e.initial.position, shift))
                entries.append(replace(e, name=name, parent=parent, initial=replace(e.initial, position=position)))
    moorings = replace(scene.moorings, body="")
    return replace(scene, bodies=tuple(entries), initial=type(scene.initial)(), constraint=type(scene.constraint)(), moorings=moorings,
                   body=type(scene.body)())  # fmt: skip


def _check_apart(device, farm) -> None:
    """Refuse a spacing at which neighbouring devices would overlap at the start: a device's reach along x and y is its
    bodies' (boxes and cubes: their half sides, or their half diagonal when turned; a mesh is not measured here)."""
    x0, y0 = (float(v) for v in device[0].initial.position[:2])
    reach = [0.0, 0.0]
    for e in device:
        if e.body.shape not in ("cube", "box"):
            return
        sides = [float(e.body.size)] * 3 if e.body.shape == "cube" else [float(v) for v in e.body.extents]
        turned = tuple(float(q) for q in e.initial.orientation) != (1.0, 0.0, 0.0, 0.0)
        half = [0.5 * (sum(s * s for s in sides) ** 0.5)] * 2 if turned else [0.5 * sides[0], 0.5 * sides[1]]
        x, y = (float(v) for v in e.initial.position[:2])
        reach = [max(reach[0], abs(x - x0) + half[0]), max(reach[1], abs(y - y0) + half[1])]
    for count, axis, r in ((farm.columns, "x", reach[0]), (farm.rows, "y", reach[1])):
        if int(count) > 1 and farm.spacing < 2.0 * r:
            raise ConfigError(f"[farm] spacing {farm.spacing:g} m: neighbouring devices overlap along {axis} (each reaches {r:g} m from "
                              f"its centre): give spacing >= {2.0 * r:g} m")  # fmt: skip
