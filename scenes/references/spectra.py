#!/usr/bin/env python3
"""Spectra as Mitsuba 3's RGB variants turn them into RGB, for ppm-vk's reader (crates/scene/src/mitsuba/spectrum.rs).

Writes spectra.json beside this script: for each case, the plugin element around the property (its tag and
type), the property element as written in the XML, and the RGB Mitsuba made of it in `scalar_rgb` (read back
with mi.traverse) -- or the error it gave. A spectrum file case reads spectra-test.spd beside this script.

The black body: Mitsuba 3's RGB variants load `<spectrum type="blackbody">` but refuse to evaluate it
("Not implemented for non-spectral modes"; this script records that). ppm-vk converts it as the spectral
variants see it: the film integrates the spectrum against the CIE curves (no D65, unbounded). The reference
for that is Mitsuba's own blackbody plugin evaluated in `scalar_spectral` at the 1000 wavelengths
spectrum_list_to_srgb integrates over, passed to Mitsuba's spectrum_list_to_srgb(bounded=False, d65=False).

Run: pip install mitsuba; DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so python3 scenes/references/spectra.py
"""
import json
import os

import mitsuba as mi

HERE = os.path.dirname(os.path.abspath(__file__))
SPD = os.path.join(HERE, "spectra-test.spd")

LIST = "400:0.3, 500:0.5, 600:0.8, 700:0.2"
# (owner tag, owner type, property XML, the traverse key)
CASES = [
    ("bsdf", "diffuse", f'<spectrum name="reflectance" value="{LIST}"/>', "reflectance.value"),
    ("bsdf", "diffuse", '<spectrum name="reflectance" value="0.4"/>', "reflectance.value"),
    ("bsdf", "diffuse", '<spectrum name="reflectance" value="500:0.9, 560:0.1"/>', "reflectance.value"),
    # A narrow green spike: out of sRGB's gamut, clamped to [0, 1].
    ("bsdf", "diffuse", '<spectrum name="reflectance" value="520:0, 530:1, 540:0"/>', "reflectance.value"),
    # Wider than the CIE range [360, 830].
    ("bsdf", "diffuse", '<spectrum name="reflectance" value="300:0.2, 900:0.9"/>', "reflectance.value"),
    ("bsdf", "diffuse", '<spectrum name="reflectance" filename="spectra-test.spd"/>', "reflectance.value"),
    ("emitter", "point", f'<spectrum name="intensity" value="{LIST}"/>', "intensity.value"),
    ("emitter", "point", '<spectrum name="intensity" value="5"/>', "intensity.value"),
    ("emitter", "point", '<spectrum name="intensity" value="520:0, 530:10, 540:0"/>', "intensity.value"),
    ("emitter", "directional", '<spectrum name="irradiance" value="400:2, 700:1"/>', "irradiance.value"),
    ("emitter", "constant", '<spectrum name="radiance" value="0.5"/>', "radiance.value"),
    ("emitter", "point", '<float name="intensity" value="5"/>', "intensity.value"),
    ("emitter", "point", '<spectrum name="intensity" filename="spectra-test.spd"/>', "intensity.value"),
    # A conductor's eta and k are unbounded (D65-weighted, clamped at 0 only).
    ("bsdf", "conductor", '<spectrum name="eta" value="400:1.2, 550:0.9, 700:0.3"/>', "eta.value"),
    ("bsdf", "conductor", '<spectrum name="k" value="400:2.5, 550:3, 700:4"/>', "k.value"),
    # Mitsuba refuses these.
    ("bsdf", "diffuse", '<spectrum name="reflectance" value="400:0.5"/>', None),
    ("bsdf", "diffuse", '<spectrum name="reflectance" value="500:0.5, 400:0.2"/>', None),
]
TEMPERATURES = [2700.0, 5000.0, 6500.0]


def rgb(v):
    # A uniform spectrum on a bsdf is Mitsuba's `uniform` texture: one float.
    if isinstance(v, float):
        return [v] * 3
    return [float(v[i]) for i in range(3)]


def load(owner, kind, prop):
    # Relative file names resolve against this folder, as against a scene's.
    mi.file_resolver().prepend(HERE)
    return mi.load_string(f'<{owner} version="3.0.0" type="{kind}">{prop}</{owner}>')


mi.set_variant("scalar_rgb")
cases = []
for owner, kind, prop, key in CASES:
    case = {"owner": owner, "type": kind, "property": prop}
    try:
        params = mi.traverse(load(owner, kind, prop))
        case["rgb"] = rgb(params[key])
    except Exception as e:  # what Mitsuba says when it refuses
        case["error"] = str(e).splitlines()[-1][:300]
    cases.append(case)

# The black body in the RGB variant: loaded, then evaluated.
bb = {}
try:
    spectrum = mi.load_dict({"type": "blackbody", "temperature": 5000.0})
    bb["rgb_variant"] = "evaluated: " + str(spectrum.eval(mi.SurfaceInteraction3f()))
except Exception as e:
    bb["rgb_variant"] = "refused: " + str(e).splitlines()[-1][:300]

mi.set_variant("scalar_spectral")
steps = 1000
wavelengths = [360.0 + (i / (steps - 1)) * (830.0 - 360.0) for i in range(steps)]
blackbodies = []
for t in TEMPERATURES:
    spec = mi.load_dict({"type": "blackbody", "temperature": t})
    values = []
    for w in wavelengths:
        si = mi.SurfaceInteraction3f()
        si.wavelengths = mi.Spectrum([w, w, w, w])
        values.append(float(spec.eval(si)[0]))
    mi.set_variant("scalar_rgb")
    color = mi.spectrum_list_to_srgb(wavelengths, values, bounded=False, d65=False)
    mi.set_variant("scalar_spectral")
    blackbodies.append({"temperature": t, "rgb": rgb(color)})
bb["spectral"] = blackbodies

with open(os.path.join(HERE, "spectra.json"), "w") as f:
    json.dump({"cases": cases, "blackbody": bb}, f, indent=1)
    f.write("\n")
print(json.dumps({"cases": cases, "blackbody": bb}, indent=1))
