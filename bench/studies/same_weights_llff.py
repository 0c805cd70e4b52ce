#!/usr/bin/env python3
"""Same-weights check on a forward-facing LLFF capture: the official google/mipnerf (JAX) model, loaded with OUR
trained weights, renders our held-out LLFF views; its images are compared with mipnerf-cl's render of the same
views (same checkpoint). With identical conventions the two differ only by float32 rounding (expected >= 60 dB).

How to run (the official code's venv has jax, flax, gin-config, numpy, pillow; bench/studies/vs_official.py makes it):

  /root/.cache/mipnerf-cl/vs-official-venv/bin/python bench/studies/same_weights_llff.py \\
      --official /tmp/official --run /tmp/from_photos/runs/given_seed0 --views 2 \\
      --device "platform=Portable Computing Language"

  (about 1.5-2 min per 504x378 view on 2 CPU cores: ~30 s ours, ~50-70 s the official model). Started with another
  python it re-executes itself in --venv. It writes bench/results/same_weights_llff/same_weights_llff.json and .md (--out-dir).

What it does:
  1. Reads the newest checkpoint of --run (format MNCKPT02; the whole-file CRC-32 is checked) and its configuration;
     stops unless the configuration is one the official MipNerfModel computes (one shared MLP, IPE, softplus
     density, blurred resampling, cylinder or cone rays, the official skip rule).
  2. Renders the first --views views of our test split with `mipnerf-cl render --split test --format exr` (EXR
     holds srgb_to_linear of the network's colour; it is converted back with the same IEC 61966-2-1 curve, in
     float64, so the compared values are the network's own outputs). --ours DIR reuses such a render.
  3. Builds the official LLFF test rays with the official loader itself (internal/datasets.py class LLFF: its
     image loading, pose rescale/recentring, llffhold 8 test split, pixel-centre rays, NDC conversion, NDC radii,
     viewdirs = the un-normalised pre-NDC world directions, near 0 / far 1 as configs/llff.gin) at the
     checkpoint's --factor. Only its 120-pose spiral is dropped (render_poses emptied before _generate_rays: it is
     only for videos and would cost GBs of rays); the test cameras' rays are computed by the unchanged code.
  4. Builds the official MipNerfModel through gin with our settings, initialises it, checks that every flax
     parameter has the shape of our layer, and replaces the values with ours: our flat buffer holds, in order,
     trunk 0..depth-1, density, bottleneck, view, rgb (host/mlp/mlp_config.hpp), each weights [in][out]
     row-major then biases [out] -- exactly flax's Dense kernel [in, out] / bias [out] of MLP_0/Dense_0..; the
     skip layer's rows are [activation | features] and the view layer's [bottleneck | view encoding], the
     official concatenation orders; our IPE/PE feature order is the official one (degree-major sin block, then
     the cos block; PE identity first).
  5. Renders the fine level of the official model with randomized=False (no stratified jitter, no density
     noise), white_bkgd=False (llff.gin), jit-compiled in chunks, and compares per view: PSNR (dB, peak 1, on
     colours clipped to [0, 1]), max |difference| in 8-bit levels (of the rounded 8-bit images), the fraction of
     pixel channels more than 1 level apart; plus the same against our 8-bit PNG when it is there.

Only the official checkout is read (sys.path); nothing is copied from it. The official side's pieces come from
bench/lib/official.py, shared with the other studies that run the official code: the import-time stand-ins it needs
with modern jax/flax (install_stubs: flax.nn names, flax.optim, cv2/matplotlib placeholders; STUBS lists them),
installed in this process's memory only; the settings check and the gin bindings (check_computable, model_settings,
bind_gin); the LLFF loader without its batch thread (llff_split).
"""

import argparse
import datetime
import glob
import json
import os
import platform
import struct
import subprocess
import sys
import time
import zlib

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # bench/: lib/
from lib import report_md  # noqa: E402
from lib.official import (DEFAULT_VENV, STUBS, OfficialError, bind_gin, check_computable,  # noqa: E402
                          install_stubs, llff_split, model_settings, official_commit)
from lib.provenance import REPO, commit_of, file_sha256  # noqa: E402


def fail(message):
    sys.exit(f"same_weights_llff.py: {message}")


def parse_args(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--official", default="/tmp/official", help="checkout of github:google/mipnerf")
    p.add_argument("--run", default="/tmp/from_photos/runs/given_seed0", help="our training --out folder")
    p.add_argument("--checkpoint", help="a .mnck file (default: the newest in --run/checkpoints)")
    p.add_argument("--data", help="LLFF folder (default: the one the checkpoint records)")
    p.add_argument("--views", type=int, default=2, help="the first N test views (official order = ours)")
    p.add_argument("--rows", help="render only rows A:B of each view on the official side (e.g. 0:64)")
    p.add_argument("--ours", help="a folder with our EXR render of the test split (skip rendering)")
    p.add_argument("--bin", default=os.path.join(REPO, "build", "mipnerf-cl"))
    p.add_argument("--device", default=os.environ.get("MIPNERF_DEVICE", "platform=Portable Computing Language"))
    p.add_argument("--venv", default=DEFAULT_VENV)
    p.add_argument("--chunk", type=int, default=4096, help="official rays per jit call")
    p.add_argument("--work", default="/tmp/same_weights_llff", help="scratch folder (our render, official npy)")
    p.add_argument("--out-dir", default=report_md.results_folder("same_weights_llff"))
    p.add_argument("--name", default="same_weights_llff", help="results file stem")
    return p.parse_args(argv)


def ensure_venv_python(args):
    try:
        import jax  # noqa: F401
        import flax  # noqa: F401
        import gin  # noqa: F401
        return
    except ImportError:
        py = os.path.join(args.venv, "bin", "python")
        if not os.path.exists(py) or os.path.realpath(sys.executable) == os.path.realpath(py):
            fail(f"needs jax, flax and gin: run with {py} (bench/studies/vs_official.py creates that venv)")
        os.execv(py, [py, os.path.abspath(__file__)] + sys.argv[1:])


# ---------------------------------------------------------------------------------------------- our checkpoint

def read_checkpoint(path):
    """Our checkpoint format 2 (host/io/checkpoint_file.hpp): magic, file bytes, header bytes, header JSON,
    float32 tensors in header order, CRC-32 of everything before it."""
    import numpy as np
    with open(path, "rb") as f:
        b = f.read()
    if b[:8] != b"MNCKPT02":
        fail(f"{path}: not a format-2 mipnerf-cl checkpoint")
    file_bytes, header_bytes = struct.unpack_from("<QQ", b, 8)
    if file_bytes != len(b) or zlib.crc32(b[:-4]) != struct.unpack_from("<I", b, len(b) - 4)[0]:
        fail(f"{path}: truncated or corrupt (size or CRC-32)")
    header = json.loads(b[24:24 + header_bytes])
    at, tensors = 24 + header_bytes, {}
    for t in header["tensors"]:
        tensors[t["name"]] = np.frombuffer(b, dtype="<f4", count=t["count"], offset=at).copy()
        at += 4 * t["count"]
    if at != len(b) - 4:
        fail(f"{path}: bytes after the last tensor")
    return header, tensors


def layer_shapes(c):
    """Our flat parameter layout (host/mlp/mlp_config.cpp parameter_layout) for a config.json."""
    input_width = 2 * 3 * (c["pos_max_deg"] - c["pos_min_deg"])
    view_width = 3 + 2 * 3 * c["view_max_deg"]
    width, depth, skip = c["mlp_width"], c["mlp_depth"], c["mlp_skip"]
    layers = []
    for i in range(depth):
        n_in = input_width if i == 0 else width
        if i > 0 and skip > 0 and (i - 1) > 0 and (i - 1) % skip == 0:
            n_in = width + input_width
        layers.append((f"trunk {i}", n_in, width))
    layers.append(("density", width, 1))
    if c["view_dependence"]:
        layers += [("bottleneck", width, width), ("view", width + view_width, c["view_branch_width"]),
                   ("rgb", c["view_branch_width"], 3)]
    else:
        layers.append(("rgb", width, 3))
    return layers


def check_config(c):
    """Stops unless the checkpoint's config is one the official MipNerfModel computes on an LLFF capture as this
    check runs it (IPE, two levels, no spherify or lindisp, black background)."""
    try:
        check_computable(c, {"single_mlp": True, "integrated_encoding": True, "pos_identity": False,
                             "multiscale": False, "resample_blur": True, "density_activation": "softplus",
                             "variant": "mipnerf", "num_levels": 2, "spherify": False, "lindisp": False})
    except OfficialError as e:
        fail(str(e))
    if c["background"] != "black":
        fail("LLFF in the official code renders on black (white_bkgd False)")


# ---------------------------------------------------------------------------------------------- our render (EXR)

def read_exr(path):
    """Scanline OpenEXR, FLOAT channels, NO or ZIP(S) compression (what our host/io/exr.cpp writes) -> dict."""
    import numpy as np
    with open(path, "rb") as f:
        b = f.read()
    if struct.unpack_from("<I", b, 0)[0] != 20000630:
        fail(f"{path}: not an OpenEXR file")
    at, attrs = 8, {}
    while b[at] != 0:
        end = b.index(b"\0", at)
        name = b[at:end].decode()
        end2 = b.index(b"\0", end + 1)
        typ = b[end + 1:end2].decode()
        size = struct.unpack_from("<i", b, end2 + 1)[0]
        attrs[name] = (typ, b[end2 + 5:end2 + 5 + size])
        at = end2 + 5 + size
    at += 1
    chans, ch = [], attrs["channels"][1]
    i = 0
    while ch[i] != 0:
        e = ch.index(b"\0", i)
        name = ch[i:e].decode()
        ptype = struct.unpack_from("<i", ch, e + 1)[0]
        if ptype != 2:
            fail(f"{path}: channel {name} is not FLOAT")
        chans.append(name)
        i = e + 1 + 16
    compression = attrs["compression"][1][0]
    x0, y0, x1, y1 = struct.unpack("<iiii", attrs["dataWindow"][1])
    w, h = x1 - x0 + 1, y1 - y0 + 1
    lines = {0: 1, 2: 1, 3: 16}.get(compression)
    if lines is None:
        fail(f"{path}: compression {compression} not supported here (NO, ZIPS, ZIP only)")
    n_chunks = (h + lines - 1) // lines
    offsets = struct.unpack_from(f"<{n_chunks}Q", b, at)
    out = {c: np.zeros((h, w), np.float32) for c in chans}
    for off in offsets:
        y, size = struct.unpack_from("<ii", b, off)
        data = b[off + 8:off + 8 + size]
        n = min(lines, y1 + 1 - y)
        raw_len = n * w * 4 * len(chans)
        if compression != 0 and size < raw_len:
            t = np.frombuffer(zlib.decompress(data), np.uint8).astype(np.int32)
            t = ((np.cumsum(t - 128) + 128) % 256).astype(np.uint8)  # undo the predictor: t[i] += t[i-1] - 128
            half = (len(t) + 1) // 2
            raw = np.empty_like(t)
            raw[0::2], raw[1::2] = t[:half], t[half:]
            data = raw.tobytes()
        arr = np.frombuffer(data, "<f4").reshape(n, len(chans), w)
        for k, c in enumerate(chans):
            out[c][y - y0:y - y0 + n] = arr[:, k]
    return out


def linear_to_srgb(x):
    """Inverse of host/io/color.cpp srgb_to_linear (float64), i.e. back to the network's colour."""
    import numpy as np
    x = x.astype(np.float64)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(np.maximum(x, 0.0031308), 1 / 2.4) - 0.055)


def render_ours(args, checkpoint):
    out = os.path.join(args.work, "ours")
    cmd = [args.bin, "--device", args.device, "render", "--checkpoint", checkpoint, "--split", "test",
           "--views", str(args.views), "--format", "both", "--out", out]
    print("+ " + " ".join(cmd), flush=True)
    t0 = time.time()
    subprocess.run(cmd, check=True)
    return out, cmd, time.time() - t0


def load_ours(folder, n):
    """Our first n test views: network colour [H, W, 3] from the EXRs (sorted by name), and the PNGs if any."""
    import numpy as np
    from PIL import Image
    exrs = sorted(glob.glob(os.path.join(folder, "**", "*.exr"), recursive=True))
    if len(exrs) < n:
        fail(f"{folder}: {len(exrs)} EXR files, need {n}")
    views = []
    for path in exrs[:n]:
        ch = read_exr(path)
        names = [k for k in ("R", "G", "B") if k in ch] or sorted(ch)[:3]
        rgb = linear_to_srgb(np.stack([ch[k] for k in names], -1))
        png_path = os.path.splitext(path)[0] + ".png"
        png = np.array(Image.open(png_path).convert("RGB")) if os.path.exists(png_path) else None
        views.append({"exr": path, "rgb": rgb, "png": png, "png_path": png_path if png is not None else None})
    return views


# ---------------------------------------------------------------------------------------------- official side

def official_rays(datasets, utils, data_dir, factor, n_views):
    """The official LLFF loader's test rays (split 'test', llffhold 8), spiral dropped, first n_views cameras."""
    cfg = utils.Config(dataset_loader="llff", factor=factor, near=0.0, far=1.0, llffhold=8, white_bkgd=False,
                       spherify=False, render_path=False)
    return llff_split(datasets, data_dir, cfg, "test", first_views=n_views)


def official_model(models, c):
    """The official MipNerfModel with our config's settings (gin-bound), and those settings. Density noise as
    ours: the official model applies it only to randomized renders, and these are not."""
    model, mlp = model_settings(c, density_noise=c["density_noise"])
    bind_gin(model, mlp)
    return models.MipNerfModel(), model, mlp


def map_weights(variables, params, c):
    """Our flat buffer -> the flax tree; every shape checked, every float used once."""
    import jax
    import numpy as np
    layers = layer_shapes(c)
    tree = jax.tree_util.tree_map(np.asarray, variables)
    dense = tree["params"]["MLP_0"]
    names = sorted(dense, key=lambda s: int(s.split("_")[1]))
    if len(names) != len(layers):
        fail(f"official MLP has {len(names)} Dense layers, ours {len(layers)}")
    at, mapping = 0, []
    for (ours, n_in, n_out), name in zip(layers, names):
        k, bias = dense[name]["kernel"], dense[name]["bias"]
        if k.shape != (n_in, n_out) or bias.shape != (n_out,):
            fail(f"{name} {k.shape}/{bias.shape} vs our {ours} ({n_in}, {n_out})")
        dense[name] = {"kernel": params[at:at + n_in * n_out].reshape(n_in, n_out),
                       "bias": params[at + n_in * n_out:at + n_in * n_out + n_out]}
        at += n_in * n_out + n_out
        mapping.append(f"{ours} [{n_in}x{n_out}] -> MLP_0/{name}")
    if at != params.size:
        fail(f"{params.size} floats in our buffer, {at} mapped")
    return tree, mapping


def render_official(model, tree, rays, chunk):
    import jax
    import jax.numpy as jnp
    import numpy as np
    from jax import random
    fn = jax.jit(lambda r: model.apply(tree, random.PRNGKey(0), r, randomized=False, white_bkgd=False)[-1][0])
    n = rays.origins.shape[0]
    out = []
    for i in range(0, n, chunk):
        part = type(rays)(*[jnp.asarray(x[i:i + chunk]) for x in rays])
        pad = chunk - part.origins.shape[0]
        if pad:
            part = type(rays)(*[jnp.pad(x, ((0, pad), (0, 0)), mode="edge") for x in part])
        out.append(np.asarray(fn(part))[:chunk - pad])
    return np.concatenate(out, 0)


# ---------------------------------------------------------------------------------------------- comparison

def compare(a, b):
    import numpy as np
    a, b = np.clip(a.astype(np.float64), 0, 1), np.clip(b.astype(np.float64), 0, 1)
    mse = float(np.mean((a - b) ** 2))
    psnr = float("inf") if mse == 0 else -10 * np.log10(mse)
    qa, qb = np.round(a * 255).astype(int), np.round(b * 255).astype(int)
    d = np.abs(qa - qb)
    return {"psnr_db": psnr, "mse": mse, "max_abs_float": float(np.abs(a - b).max()),
            "max_abs_8bit_levels": int(d.max()), "fraction_over_1_level": float(np.mean(d > 1)),
            "fraction_any_level": float(np.mean(d > 0))}


def compare_png(official, png):
    import numpy as np
    q = np.round(np.clip(official.astype(np.float64), 0, 1) * 255).astype(int)
    d = np.abs(q - png.astype(int))
    mse = float(np.mean(((q - png.astype(int)) / 255.0) ** 2))
    return {"psnr_db": float("inf") if mse == 0 else -10 * np.log10(mse), "max_abs_8bit_levels": int(d.max()),
            "fraction_over_1_level": float(np.mean(d > 1))}


def fmt_db(x):
    return "inf" if x == float("inf") else f"{x:.2f}"


def write_md(path, doc):
    lines = ["# Same weights, official mip-NeRF vs mipnerf-cl, forward-facing LLFF", "",
             f"Generated by `bench/studies/same_weights_llff.py` on {doc['date']} (mipnerf-cl {doc['commit']}, our device "
             f"{doc['device']!r}).", "",
             f"Command: `{doc['command']}`", "",
             f"mipnerf-cl executable: `{doc['binary']}` (sha256 {doc['binary_sha256'][:16]}..., built "
             f"{doc['binary_mtime']}).", "",
             f"Checkpoint: `{doc['checkpoint']}` (step {doc['step']}); data `{doc['data']}`, factor "
             f"{doc['factor']}, test views = every 8th image (official llffhold 8), first {doc['views']}; "
             f"pixels compared: {doc['pixels_note']}.", "",
             "Official side: google/mipnerf MipNerfModel (fine level), randomized=False (no jitter, no density "
             "noise), white_bkgd=False, rays from the official LLFF loader (NDC, NDC radii, viewdirs = "
             "un-normalised world directions), our weights mapped layer by layer (shapes checked).", ""]
    rows = []
    for v in doc["per_view"]:
        m, p = v["vs_exr"], v.get("vs_png") or {}
        rows.append([str(v["test_index"]), str(v["image"]), str(v["size"]), fmt_db(m["psnr_db"]),
                     f"{m['max_abs_float']:.2e}", str(m["max_abs_8bit_levels"]),
                     f"{100 * m['fraction_over_1_level']:.4f} %", f"{100 * m['fraction_any_level']:.4f} %",
                     fmt_db(p.get("psnr_db", float("nan"))), str(p.get("max_abs_8bit_levels", "-"))])
    lines += report_md.table(["view", "image", "size", "PSNR (dB)", "max abs diff (float)",
                              "max abs diff (8-bit levels)", "pixel channels > 1 level off", "any level off",
                              "PSNR vs our PNG (dB)", "max vs PNG"], "l" * 10, rows)
    lines += ["", f"Verdict: {doc['verdict']}", ""]
    if doc.get("notes"):
        lines += ["## Notes", ""] + [f"- {n}" for n in doc["notes"]] + [""]
    with open(path, "w") as f:
        f.write("\n".join(lines))


def main(argv):
    args = parse_args(argv)
    ensure_venv_python(args)
    import numpy as np

    # 1. our checkpoint
    from_run = os.path.join(args.run, "checkpoints")
    ckpt = args.checkpoint or sorted(glob.glob(os.path.join(from_run, "ckpt_*.mnck")))[-1]
    header, tensors = read_checkpoint(ckpt)
    c = header["config"]
    check_config(c)
    params = tensors["network0.params"]
    if any(k.startswith("network1.") for k in tensors):
        fail("two networks in the checkpoint; the official model shares one MLP")
    data = args.data or header.get("data") or fail("pass --data")
    os.makedirs(args.work, exist_ok=True)

    # 2. our render
    ours_cmd, ours_seconds = None, None
    if args.ours:
        ours_dir = args.ours
    else:
        ours_dir, ours_cmd, ours_seconds = render_ours(args, ckpt)
    ours = load_ours(ours_dir, args.views)

    # 3-5. official side
    sys.path.insert(0, os.path.abspath(args.official))
    install_stubs()
    import jax
    from jax import random
    from internal import datasets, models, utils
    ds = official_rays(datasets, utils, data, c["factor"], args.views)
    h, w = ds.h, ds.w
    model, model_bound, mlp_bound = official_model(models, c)
    flat = utils.namedtuple_map(lambda r: np.asarray(r, np.float32).reshape(args.views, h, w, -1), ds.rays)
    example = utils.namedtuple_map(lambda r: r[0, 0, :2].reshape(2, -1), flat)
    variables = model.init(random.PRNGKey(0), rng=random.PRNGKey(1), rays=example, randomized=False,
                           white_bkgd=False)
    tree, mapping = map_weights(variables, params, c)
    r0, r1 = (0, h) if not args.rows else map(int, args.rows.split(":"))
    per_view, t0 = [], time.time()
    test_indices = np.arange(len(sorted(f for f in os.listdir(os.path.join(data, f"images_{c['factor']}"))
                                        if f.endswith(("JPG", "jpg", "png")))))[::8]
    image_names = sorted(f for f in os.listdir(os.path.join(data, f"images_{c['factor']}"))
                         if f.endswith(("JPG", "jpg", "png")))
    for v in range(args.views):
        rays = utils.namedtuple_map(lambda r: r[v, r0:r1].reshape(-1, r.shape[-1]), flat)
        t = time.time()
        rgb = render_official(model, tree, rays, args.chunk).reshape(r1 - r0, w, 3)
        secs = time.time() - t
        np.save(os.path.join(args.work, f"official_{v:03d}.npy"), rgb)
        mine = ours[v]["rgb"]
        if mine.shape[:2] != (h, w):
            fail(f"our view {v} is {mine.shape[:2]}, the official {(h, w)}")
        entry = {"test_index": v, "image": image_names[test_indices[v]], "size": f"{w}x{h}",
                 "rows": [r0, r1], "exr": ours[v]["exr"], "official_seconds": secs,
                 "vs_exr": compare(rgb, mine[r0:r1])}
        if ours[v]["png"] is not None:
            entry["vs_png"] = compare_png(rgb, ours[v]["png"][r0:r1])
        # Where the differences are: per-channel mean signed difference, worst pixel.
        d = np.abs(np.clip(rgb, 0, 1) - np.clip(mine[r0:r1], 0, 1)).max(-1)
        y, x = np.unravel_index(np.argmax(d), d.shape)
        entry["worst_pixel"] = {"row": int(y + r0), "col": int(x), "official": rgb[y, x].tolist(),
                                "ours": mine[r0 + y, x].tolist()}
        entry["mean_signed_diff_official_minus_ours"] = (rgb - mine[r0:r1]).reshape(-1, 3).mean(0).tolist()
        per_view.append(entry)
        print(f"view {v} ({entry['image']}): PSNR {fmt_db(entry['vs_exr']['psnr_db'])} dB, max "
              f"{entry['vs_exr']['max_abs_8bit_levels']} levels, >1 level "
              f"{100 * entry['vs_exr']['fraction_over_1_level']:.4f} % ({secs:.0f} s official)", flush=True)

    worst = min(v["vs_exr"]["psnr_db"] for v in per_view)
    verdict = (f"PASS: every view >= 60 dB (worst {fmt_db(worst)} dB)" if worst >= 60 else
               f"BELOW 60 dB (worst {fmt_db(worst)} dB): a convention differs, see notes")
    commit = commit_of(REPO)
    import flax
    doc = {"format": 1, "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
           "commit": commit, "device": args.device, "command": " ".join([os.path.basename(sys.executable)] +
                                                                        [os.path.relpath(__file__, REPO)] + argv),
           "binary": args.bin, "binary_sha256": file_sha256(args.bin),
           "binary_mtime": datetime.datetime.fromtimestamp(os.path.getmtime(args.bin), datetime.timezone.utc)
           .isoformat(timespec="seconds"),
           "our_render_command": ours_cmd and " ".join(ours_cmd), "our_render_seconds": ours_seconds,
           "checkpoint": ckpt, "step": header.get("step"), "data": data, "factor": c["factor"],
           "views": args.views, "pixels_note": "all pixels of each view" if not args.rows else
           f"rows {r0}:{r1} of each view", "official": os.path.abspath(args.official),
           "official_commit": official_commit(args.official), "stubs": [{"name": n, "what": w} for n, w in STUBS],
           "official_model_settings": model_bound, "official_mlp_settings": mlp_bound,
           "weight_mapping": mapping, "our_config": c, "per_view": per_view, "verdict": verdict,
           "versions": {"python": platform.python_version(), "jax": jax.__version__, "flax": flax.__version__,
                        "numpy": np.__version__},
           "notes": ["PSNR over colours clipped to [0, 1], peak 1; 8-bit levels from round(255 * clip(x)).",
                     "Our colour is read from the EXR (srgb_to_linear of the network's output) and converted "
                     "back in float64; 'vs our PNG' compares the official 8-bit rounding with our PNG."]}
    os.makedirs(args.out_dir, exist_ok=True)
    stem = os.path.join(args.out_dir, args.name)
    with open(stem + ".json", "w") as f:
        json.dump(doc, f, indent=1)
    write_md(stem + ".md", doc)
    print(f"{verdict}\nwrote {stem}.json and {stem}.md")


if __name__ == "__main__":
    main(sys.argv[1:])
