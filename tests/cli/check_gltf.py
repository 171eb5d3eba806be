#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Check a glint glTF export against glint's material, independently.

  check_gltf.py MATERIAL.json EXPORT.gltf

Both BRDFs are written here from their published equations, sharing no
code with glint: Torrance-Sparrow as Joshi & Jensen / Cook & Torrance state
it (Beckmann D with RMS slope m, V-cavity G, exact unpolarised dielectric
Fresnel) and glTF 2.0's metallic-roughness dielectric with
KHR_materials_ior and KHR_materials_specular (specification Appendix B).
The relative RMS difference of reflected radiance under uniform light is
integrated on a grid of half vectors at glint's 8 view angles and
must agree with the residual the export states (within 25 % + 0.01); the
refit must also beat copying the numbers across (roughness = sqrt(m),
specular colour = the specular albedo).  Prints both numbers.
"""
import json
import math
import sys


def fresnel(c, n):
    c = min(abs(c), 1.0)
    g = math.sqrt(n * n - 1 + c * c)
    a = (g - c) / (g + c)
    b = (c * (g + c) - 1) / (c * (g - c) + 1)
    return 0.5 * a * a * (1 + b * b)


def ts(mat, wo, wi):
    kd, ks, m, n = mat["diffuse"], mat["specular"], mat["roughness"], mat["ior"]
    h = [wo[i] + wi[i] for i in range(3)]
    hl = math.sqrt(sum(x * x for x in h))
    h = [x / hl for x in h]
    nh, no, ni = h[2], wo[2], wi[2]
    oh = sum(wo[i] * h[i] for i in range(3))
    t2 = (1 - nh * nh) / (nh * nh)
    d = math.exp(-t2 / (m * m)) / (math.pi * m * m * nh ** 4)
    g = min(1.0, 2 * nh * no / oh, 2 * nh * ni / oh)
    s = d * g * fresnel(oh, n) / (4 * ni * no)
    return [kd[c] / math.pi + ks[c] * s for c in range(3)]


def gltf(mat, wo, wi):
    pbr = mat["pbrMetallicRoughness"]
    ext = mat["extensions"]
    base = pbr["baseColorFactor"][:3]
    a = pbr["roughnessFactor"] ** 2
    a2 = a * a
    ior = ext["KHR_materials_ior"]["ior"]
    spec = ext["KHR_materials_specular"]["specularFactor"]
    scol = ext["KHR_materials_specular"]["specularColorFactor"]
    h = [wo[i] + wi[i] for i in range(3)]
    hl = math.sqrt(sum(x * x for x in h))
    h = [x / hl for x in h]
    nl, nv, nh = wi[2], wo[2], h[2]
    vh = abs(sum(wo[i] * h[i] for i in range(3)))
    d = a2 / (math.pi * (nh * nh * (a2 - 1) + 1) ** 2)
    v = 1 / ((nl + math.sqrt(a2 + (1 - a2) * nl * nl)) *
             (nv + math.sqrt(a2 + (1 - a2) * nv * nv)))
    f0r = ((ior - 1) / (ior + 1)) ** 2
    out = []
    for c in range(3):
        f0 = min(f0r * scol[c], 1.0) * spec
        F = f0 + (spec - f0) * (1 - vh) ** 5
        out.append((1 - F) * base[c] / math.pi + F * d * v)
    return out


def rel_rms(mat, exp, nt=100, nphi=120):
    """Over half vectors h (wi = o reflected about h, dwi = 4 (o.h) dwh),
    theta_h = (pi/2) s^2 so the steps are finest at the lobe's peak."""
    num = den = 0.0
    for o in range(8):
        t = math.radians(5 + 10 * o)
        wo = (math.sin(t), 0.0, math.cos(t))
        for j in range(nt):
            sj = (j + 0.5) / nt
            th = math.pi / 2 * sj * sj
            dth = math.pi * sj / nt
            for k in range(nphi):
                p = (k + 0.5) / nphi * 2 * math.pi
                h = (math.sin(th) * math.cos(p), math.sin(th) * math.sin(p),
                     math.cos(th))
                oh = sum(wo[i] * h[i] for i in range(3))
                wi = tuple(2 * oh * h[i] - wo[i] for i in range(3))
                if oh <= 0 or wi[2] <= 0:
                    continue
                dw = 4 * oh * math.sin(th) * dth * 2 * math.pi / nphi
                f = ts(mat, wo, wi)
                g = gltf(exp, wo, wi)
                for c in range(3):
                    num += ((g[c] - f[c]) * wi[2]) ** 2 * dw
                    den += (f[c] * wi[2]) ** 2 * dw
    return math.sqrt(num / den)


def main():
    mat = json.load(open(sys.argv[1]))
    mat = mat.get("material", mat)  # a fit's params.json, or a material
    assert mat["model"] == "torrance-sparrow", mat["model"]
    # The grid resolves lobes of RMS slope 0.02 and up.
    assert mat["roughness"] >= 0.02, mat["roughness"]
    doc = json.load(open(sys.argv[2]))
    assert doc["asset"]["version"] == "2.0", doc["asset"]
    assert set(doc["extensionsUsed"]) >= {"KHR_materials_ior",
                                          "KHR_materials_specular"}
    exp = doc["materials"][0]
    pbr = exp["pbrMetallicRoughness"]
    assert pbr["metallicFactor"] == 0 and len(pbr["baseColorFactor"]) == 4
    stated = exp["extras"]["glint"]["refit_relative_rms"]
    got = rel_rms(mat, exp)
    naive = json.loads(json.dumps(exp))
    naive["pbrMetallicRoughness"]["roughnessFactor"] = math.sqrt(mat["roughness"])
    naive["pbrMetallicRoughness"]["baseColorFactor"] = mat["diffuse"] + [1]
    sp = sum(mat["specular"]) / 3
    naive["extensions"]["KHR_materials_specular"] = {
        "specularFactor": sp,
        "specularColorFactor": [x / sp for x in mat["specular"]]}
    copied = rel_rms(mat, naive)
    print(f"stated {stated:.4f}, independent {got:.4f}, copied across "
          f"{copied:.4f}")
    assert abs(got - stated) <= 0.25 * stated + 0.01, (got, stated)
    assert got < copied, (got, copied)


main()
