"""Share a setup as a link: `?scene=drop&density=500` opens the viewer on that preset with those
parameters, and "Copy link" writes the running ones.

viser does not pass the page's address to the server, so each new page runs a few lines of script
(viser's RunJavascriptMessage, the channel it uses itself for plotly) that put `location.search` into a
probe text input of that page only; the server reads it from there, applies it and removes the probe.
"""

from __future__ import annotations

import functools
import json
from urllib.parse import parse_qsl, urlencode

import viser
from viser import _messages

from app.live.loop import CONTROLLED, DERIVED, SPEED, Settings
from sim.errors import ConfigError
from sim.scene.config import body_own, entry_value, in_effect, load_scene, with_overrides

PROBE = "floatsim-address"
VISER_PARAMS = {
    "fixedDpr",
    "darkMode",
    "showStats",
    "websocket",
    "logCamera",
    "playbackPath",
    "synchronizedVideoOverlay",
    "initialCameraPosition",
    "initialCameraLookAt",
    "initialCameraUp",
    "forceOrbitOriginTool",
}
"""The page address's parameters that viser's client reads itself: not part of a setup."""

_PROBE_JS = """(function(){
  var t0 = Date.now();
  var timer = setInterval(function(){
    var label = Array.from(document.querySelectorAll('label')).find(function(l){ return l.textContent.trim() === %(probe)s; });
    if (!label) { if (Date.now() - t0 > 30000) clearInterval(timer); return; }
    clearInterval(timer);
    var row = label.closest('p').parentElement.parentElement;  // label column's row: the input is its sibling
    var input = row.querySelector('input');
    row.style.display = 'none';
    var set = Object.getOwnPropertyDescriptor(HTMLInputElement.prototype, 'value').set;
    set.call(input, location.search || '?');
    input.dispatchEvent(new Event('input', {bubbles: true}));
  }, 100);
})();"""


def parse_link(query: str, scene_options: tuple[str, ...]) -> tuple[list[tuple[str, object]], list[str]]:
    """The loop commands a link's query asks for (scene first) and what in it was refused: unknown keys,
    values that are not numbers or choices or lie outside the control's range, and repeats of a key
    (the first one counts). A body's own parameter in a scene of several is BODY.key (float.density=700): the commands
    choose that body, then set it. Nothing refused reaches the run."""
    commands, problems, seen, bodies = [], [], set(), ()
    pairs = parse_qsl(query.lstrip("?"), keep_blank_values=True)
    for key, text in sorted(pairs, key=lambda kv: kv[0] != "scene"):  # stable: the first of a repeated key stays first
        if key in VISER_PARAMS or key == "token":  # viser's own, and the viewer's access token (app/main.py)
            continue
        if key in seen:
            problems.append(f"{key[:30]!r} given more than once (the first kept)")
            continue
        seen.add(key)
        if key == "scene":
            if text in scene_options:
                commands.append(("scene", text))
                bodies = tuple(e.name for e in preset.bodies) if (preset := _preset(text)) is not None else ()
            else:
                problems.append(f"scene {text[:30]!r} is not a preset")
            continue
        body, _, name = key.rpartition(".")
        param = SPEED if key == "speed" else CONTROLLED.get(name)
        if param is None or (body and not body_own(param)):
            problems.append(f"unknown parameter {key[:30]!r}")
            continue
        if body not in ("", *bodies) or (bodies and not body and body_own(param)):
            problems.append(
                f"{key[:30]!r}: a body's own parameter is BODY.{name}, BODY one of the scene's bodies ({', '.join(bodies) or 'none'})"
            )
            continue
        value, why = _link_value(param, text)
        if why:
            problems.append(why)
        else:
            commands += [("focus", body), (name, value)] if body else [(name, value)]
    return commands, problems


def _link_value(param, text: str):
    """(value, None) when `text` is a value the control takes as it is; (None, why) when not."""
    try:
        if param.kind == "choice":
            value = text
        elif param.kind == "switch":
            value = {"true": True, "false": False}.get(text.lower(), text)
        elif param.kind == "vector":
            value = tuple(float(v) for v in text.split(","))
        else:
            value = float(text)
    except ValueError:
        return None, f"{param.key} = {text[:30]!r} is not a number"
    used, note = param.clamp(value, None)
    if note is not None or used is None:  # the clamp would change it: a link carries only values it keeps
        return None, (note or f"{param.key} = {text[:30]!r} is not accepted").split(";")[0]
    return used, None


@functools.lru_cache(maxsize=32)
def _preset(name: str):
    try:
        return load_scene(name)
    except Exception:  # noqa: BLE001 -- a scene file that went away: the link gives every value
        return None


def link_query(settings: Settings) -> str:
    """The query that reproduces the running setup: the preset and every controlled parameter that
    differs from it (a loaded mesh lives on this server only: it is not part of the link; in a scene of several bodies
    each body's own as BODY.key). A value other parameters decide (`IN_EFFECT`) is compared with what the link's scene
    would have in effect."""
    preset = _preset(settings.scene)
    keys = [k for k in CONTROLLED if not (settings.config.bodies and body_own(CONTROLLED[k]))]  # a body's own: _body_pairs
    written = {key: _shown(settings, key) for key in set(keys) - DERIVED}
    written = {key: v for key, v in written.items() if preset is None or v != in_effect(preset, _qualname(key))}
    target = preset
    try:
        target = preset and with_overrides(preset, **{_qualname(key).replace(".", "__"): v for key, v in written.items()})
    except ConfigError:  # (the run took each of these values, so the preset should too: then the link gives every value)
        target = None
    derived = {key: settings.value(key) for key in DERIVED if key in keys}
    differ = written | {key: v for key, v in derived.items() if target is None or v != in_effect(target, _qualname(key))}
    pairs = [("scene", settings.scene)] + [(key, _text(CONTROLLED[key], differ[key])) for key in CONTROLLED if key in differ]
    pairs += _body_pairs(settings.config, preset)
    if settings.speed != 1.0:
        pairs.append(("speed", f"{settings.speed:g}"))
    return "?" + urlencode(pairs, safe=",")


def _body_pairs(config, preset) -> list[tuple[str, str]]:
    """(BODY.key, text) of each body's own controlled parameter that differs from the preset's (a density only where the
    body gives one, not a mass)."""
    if not config.bodies:
        return []
    given = {e.name: e for e in preset.bodies} if preset is not None else {}
    pairs = []
    for entry in config.bodies:
        for key, param in CONTROLLED.items():
            if not body_own(param) or (key == "density" and entry.body.mass is not None):
                continue
            value, old = entry_value(config, entry, key), given.get(entry.name)
            if old is None or value != entry_value(preset, old, key):
                pairs.append((f"{entry.name}.{key}", _text(param, value)))
    return pairs


def _qualname(key: str) -> str:
    return f"{CONTROLLED[key].section}.{key}"


def _shown(settings: Settings, key: str):
    if key == "density":  # the scene's own density where it gives one (a mass given makes it derived)
        return settings.config.body.density if settings.config.body.mass is None else settings.density
    return settings.value(key)


def _text(param, value) -> str:
    if param.kind == "switch":
        return str(value).lower()
    if param.kind == "vector":
        return ",".join(f"{v:g}" for v in value)
    return f"{value:.6g}" if isinstance(value, float) else str(value)


def mesh_left_out(settings: Settings) -> bool:
    """Whether the running body is a mesh the link cannot carry (loaded here, not the preset's)."""
    preset = _preset(settings.scene)
    if settings.value("shape") != "mesh":
        return False
    if settings.config.bodies:
        entry = next((e for e in preset.bodies if e.name == settings.focus), None) if preset is not None else None
        return entry is None or entry.body.mesh != settings.value("mesh")
    return preset is None or preset.body.mesh != settings.config.body.mesh


def copy_button_html(query: str) -> str:
    """A button that copies this page's address with `query` (a prompt to copy by hand where the
    clipboard is not allowed, as on plain http from another machine)."""
    js = (f"var u=location.origin+location.pathname+{json.dumps(query)};var b=this;"
          "(navigator.clipboard?navigator.clipboard.writeText(u):Promise.reject()).then("
          "function(){b.textContent='Link copied';setTimeout(function(){b.textContent='Copy link'},2000)},"
          "function(){window.prompt('Copy this link',u)})")  # fmt: skip
    style = ("width:100%;padding:0.35em;border-radius:4px;border:1px solid #ced4da;background:#f8f9fa;cursor:pointer;"
             "font:inherit;font-size:0.85em")  # fmt: skip
    return f'<button type="button" style="{style}" onclick="{js.replace(chr(34), "&quot;")}">Copy link</button>'


def probe_address(client: viser.ClientHandle, on_address) -> None:
    """Ask this page for its address; `on_address(client, query)` gets it ('?' when there is none)."""
    probe = client.gui.add_text(PROBE, "", order=1e9)

    def read(event) -> None:
        query = probe.value
        if not query:
            return
        probe.remove()
        on_address(client, query)

    probe.on_update(read)
    client._websock_connection.queue_message(_messages.RunJavascriptMessage(source=_PROBE_JS % {"probe": json.dumps(PROBE)}))
