"""The interior (scenes/interior.xml) with one kind of surface at a time made diffuse, for run.sh."""
import os
import re

here = os.path.dirname(os.path.abspath(__file__))
src = open(os.path.join(here, "../../../../scenes/interior.xml")).read()
src = src.replace('value="meshes/', 'value="../../../../scenes/meshes/')
src = src.replace('value="textures/', 'value="../../../../scenes/textures/')
WOOD = r'<bsdf type="roughplastic">.*?</bsdf>'
METAL = r'<bsdf type="roughconductor" id="metal">.*?</bsdf>'
GLASS = r'<bsdf type="dielectric" id="glass">.*?</bsdf>'
TEXTURE = r'<texture type="bitmap" name="diffuse_reflectance">.*?</texture>'
GREY = '<bsdf type="diffuse" id="{}"><rgb name="reflectance" value="0.8"/></bsdf>'
WOOD_COLOUR = '0.45, 0.3, 0.18'


def sub(pattern, repl, s):
    out = re.sub(pattern, repl, s, flags=re.S)
    assert out != s, pattern
    return out


variants = {
    "as-is": src,
    "wood-untextured": sub(TEXTURE, f'<rgb name="diffuse_reflectance" value="{WOOD_COLOUR}"/>', src),
    "wood-nearest": sub(
        r'(<texture type="bitmap" name="diffuse_reflectance">)',
        r'\1<string name="filter_type" value="nearest"/>',
        src,
    ),
    "wood-diffuse": sub(
        WOOD,
        '<bsdf type="diffuse"><texture type="bitmap" name="reflectance">'
        '<string name="filename" value="../../../../scenes/textures/wood.png"/></texture></bsdf>',
        src,
    ),
    "metal-diffuse": sub(METAL, GREY.format("metal"), src),
    "glass-diffuse": sub(GLASS, GREY.format("glass"), src),
}
all_diffuse = sub(METAL, GREY.format("metal"), src)
all_diffuse = sub(GLASS, GREY.format("glass"), all_diffuse)
variants["all-diffuse"] = sub(WOOD, f'<bsdf type="diffuse"><rgb name="reflectance" value="{WOOD_COLOUR}"/></bsdf>', all_diffuse)
for name, text in variants.items():
    with open(os.path.join(here, f"interior-{name}.xml"), "w") as f:
        f.write(text)
