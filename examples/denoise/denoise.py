#!/usr/bin/env python3
"""Denoise an rtow render with Intel Open Image Denoise, from its feature buffers.

    rtow render final --aov albedo,normal -o final.pfm      # final.pfm, final.albedo.pfm, final.normal.pfm
    python3 examples/denoise/denoise.py final.pfm final-denoised.pfm
    rtow diff final-denoised.pfm reference.pfm               # how close it came

Needs numpy and the `oidn` package from PyPI (`pip install oidn numpy`: Open
Image Denoise 1.4.3 built for x86-64 Linux, macOS and Windows). rtow does not
depend on either. The feature buffers are found beside the colour image
(`x.pfm` -> `x.albedo.pfm`, `x.normal.pfm`); without them the colour is
denoised alone (`--no-aux`). The colour is linear HDR (OIDN's `hdr` mode);
the output is a linear PFM, which `rtow diff` reads and any HDR viewer shows.
"""

import argparse
import ctypes
import pathlib
import sys

import numpy as np


def read_pfm(path):
    """A PFM file as an array of rows top first, (height, width, channels) float32."""
    data = pathlib.Path(path).read_bytes()
    magic, size, scale, body = data.split(b"\n", 3)
    channels = {b"PF": 3, b"Pf": 1}[magic]
    width, height = map(int, size.split())
    dtype = "<f4" if float(scale) < 0 else ">f4"
    pixels = np.frombuffer(body, dtype=dtype, count=width * height * channels)
    return pixels.reshape(height, width, channels)[::-1].astype(np.float32)


def write_pfm(path, image):
    height, width, _ = image.shape
    header = f"PF\n{width} {height}\n-1.0\n".encode()
    body = np.ascontiguousarray(image[::-1], dtype="<f4").tobytes()
    pathlib.Path(path).write_bytes(header + body)


def beside(colour, name):
    """rtow's name for feature buffer `name` beside the image `colour`."""
    return colour.with_suffix(f".{name}.pfm")


def denoise(colour, albedo=None, normal=None):
    import oidn

    lib = getattr(oidn, "__lib_oidn")
    lib.oidnSetFilter1b.argtypes = [ctypes.c_void_p, ctypes.c_char_p, ctypes.c_bool]
    height, width, _ = colour.shape
    output = np.zeros_like(colour)
    device = oidn.NewDevice()
    oidn.CommitDevice(device)
    filt = oidn.NewFilter(device, "RT")
    oidn.SetSharedFilterImage(filt, "color", colour, oidn.FORMAT_FLOAT3, width, height)
    if albedo is not None:
        oidn.SetSharedFilterImage(filt, "albedo", albedo, oidn.FORMAT_FLOAT3, width, height)
        if normal is not None:
            oidn.SetSharedFilterImage(filt, "normal", normal, oidn.FORMAT_FLOAT3, width, height)
    oidn.SetSharedFilterImage(filt, "output", output, oidn.FORMAT_FLOAT3, width, height)
    lib.oidnSetFilter1b(filt, b"hdr", True)
    oidn.CommitFilter(filt)
    oidn.ExecuteFilter(filt)
    error = oidn.GetDeviceError(device)
    oidn.ReleaseFilter(filt)
    oidn.ReleaseDevice(device)
    if error != 0:
        sys.exit(f"error: Open Image Denoise failed (error {error})")
    return output


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("colour", type=pathlib.Path, help="rtow's linear image (.pfm)")
    p.add_argument("output", type=pathlib.Path, help="the denoised image (.pfm)")
    p.add_argument("--no-aux", action="store_true", help="ignore the feature buffers")
    a = p.parse_args()
    colour = read_pfm(a.colour)
    albedo = normal = None
    if not a.no_aux:
        for name in ("albedo", "normal"):
            if not beside(a.colour, name).exists():
                sys.exit(f"error: {beside(a.colour, name)} not found: render with --aov albedo,normal (or give --no-aux)")
        albedo, normal = read_pfm(beside(a.colour, "albedo")), read_pfm(beside(a.colour, "normal"))
    write_pfm(a.output, denoise(colour, albedo, normal))


if __name__ == "__main__":
    main()
