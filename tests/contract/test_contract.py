# SPDX-License-Identifier: Apache-2.0
"""The contract suite: property tests over the whole API through the Python
binding (README.md in this folder).

Every test draws options, values and call sequences anywhere inside the
documented ranges, their ends included (and some values just outside), and
checks after every call what the headers promise:
  - no crash, and no exception but a refusal (contract.call);
  - a status and a message naming the function or argument for every
    refusal, never FLT_ERR_INTERNAL;
  - a NaN only with its flag (recon.h, extractor.h, flatness.h), every
    other output finite;
  - a bounded time per row (contract.FIXED_SECONDS, SECONDS_PER_ROW);
  - the handle usable, and unchanged, after a refused call.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, example, given, note, settings
from hypothesis import strategies as st
from hypothesis.stateful import (RuleBasedStateMachine, invariant, precondition, rule)

import flatline
from flatline import capi

from conftest import examples
from contract import (NAN_FLAGS, OPTIONS, SCALES, Tally, assert_nan_flagged, block, call,
                      closing, option_value, options_of, out_of_range, positions, trim_heap)


def teardown_module(module):
    print(f"\ncontract suite: {Tally.calls} checked calls; refusals by kind: "
          f"{dict(sorted(Tally.refused.items()))}")


# -- options ------------------------------------------------------------------------


@settings(max_examples=examples(300))
@given(name=st.sampled_from(sorted(OPTIONS)), data=st.data())
@closing
def test_every_option_takes_its_range_and_refuses_the_rest(name, data):
    info = OPTIONS[name]
    bag = capi.flt_options_create()
    value = data.draw(option_value(name), label="value")
    ok, _ = call("flt_options_set", capi.flt_options_set, bag, info.key, value)
    assert ok, f"{name} = {value!r} is inside [{info.min_value}, {info.max_value}]"
    assert capi.flt_options_get(bag, info.key) == value
    bad = data.draw(out_of_range(name), label="bad")
    ok, error = call("flt_options_set", capi.flt_options_set, bag, info.key, bad)
    assert not ok and isinstance(error, flatline.InvalidArgumentError)
    assert name in str(error)
    assert capi.flt_options_get(bag, info.key) == value  # unchanged by the refusal


# -- calibration ------------------------------------------------------------------

REFERENCE = flatline.Calibration.reference()
REFERENCE_H = [REFERENCE.homography(0), REFERENCE.homography(1)]


def in_or_out(inside, outside):
    """Mostly `inside`, one time in seven `outside` (values a setter must
    refuse)."""
    return st.integers(0, 6).flatmap(lambda i: outside if i == 0 else inside)


def floats_in(lo, hi, *extra):
    return st.one_of(st.just(lo), st.just(hi),
                     st.floats(lo, hi, allow_nan=False, allow_infinity=False),
                     *[st.just(x) for x in extra])


def magnitude(lo, hi):
    """A value whose |value| lies in [lo, hi], log-spread, either sign."""
    return st.tuples(st.floats(math.log10(lo), math.log10(hi)), st.booleans()).map(
        lambda t: min(hi, max(lo, 10.0 ** t[0])) * (-1 if t[1] else 1))


BAD_FLOATS = st.sampled_from([math.nan, math.inf, -math.inf, 1e300, -1e300, 1e-300])

FRAME_SIDE = in_or_out(
    st.one_of(st.just(1), st.just(flatline.capi.FLT_CALIB_MAX_FRAME_SIDE),
              st.integers(1, 4096)),
    st.sampled_from([0, capi.FLT_CALIB_MAX_FRAME_SIDE + 1, 65536, 2**32 - 1, 2**32, -1]))
FOCAL = in_or_out(st.one_of(floats_in(1.0, 1e6, 1090.9), magnitude(1.0, 1e6).map(abs)),
                  st.one_of(BAD_FLOATS, st.just(0.5), st.just(-1000.0)))
CENTRE = in_or_out(floats_in(-65536.0, 65536.0, 1024.0), BAD_FLOATS)
RADIAL = in_or_out(st.one_of(st.just(0.0), floats_in(-1000.0, 1000.0), magnitude(1e-9, 1e3)),
                   st.one_of(BAD_FLOATS, st.just(1000.5)))
TANGENTIAL = in_or_out(st.one_of(st.just(0.0), floats_in(-1.0, 1.0), magnitude(1e-9, 1.0)),
                       st.one_of(BAD_FLOATS, st.just(1.5)))
OFFSET = in_or_out(floats_in(-1e4, 1e4, -50.0, 50.0), st.one_of(BAD_FLOATS, st.just(-10001.0)))
SPACING = st.one_of(st.just(1.0), st.just(-1.0), st.just(100.0), st.just(0.5),
                    st.floats(-2e4, 2e4, allow_nan=False))
ENCODER = in_or_out(magnitude(1e-9, 1e6), st.one_of(BAD_FLOATS, st.just(0.0)))
FIRST_X = in_or_out(floats_in(-1e5, 1e5, -1000.0), BAD_FLOATS)
PITCH = in_or_out(st.one_of(floats_in(1e-3, 1e4, 2.0), magnitude(1e-3, 1e4).map(abs)),
                  st.one_of(BAD_FLOATS, st.just(0.0), st.just(-2.0), st.just(1e-4)))
COUNT = in_or_out(st.one_of(st.just(1), st.just(capi.FLT_MAX_FIBERS), st.integers(1, 2048)),
                  st.sampled_from([0, capi.FLT_MAX_FIBERS + 1, 10**8, 2**64, -1]))


@st.composite
def homographies(draw):
    kind = draw(st.integers(0, 3))
    laser = draw(st.integers(0, 1))
    if kind == 0:  # the reference's, scaled anywhere in (and just out of) range
        exponent = draw(st.sampled_from([-100.0, -99.0, 0.0, 99.0, 99.5, 100.0]) |
                        st.floats(-101, 101))
        return REFERENCE_H[laser] * 10.0 ** exponent
    if kind == 1:  # a random matrix (maybe near singular)
        seed = draw(st.integers(0, 2**32 - 1))
        return np.random.default_rng(seed).normal(size=(3, 3)) * 10.0 ** draw(
            st.integers(-3, 3))
    if kind == 2:  # the reference perturbed
        seed = draw(st.integers(0, 2**32 - 1))
        return REFERENCE_H[laser] * (1 + 0.1 * np.random.default_rng(seed).normal(size=(3, 3)))
    return np.eye(3) * draw(st.sampled_from([1.0, 1e-100, 1e100, 1e101, 1e-101]))


@st.composite
def calibration_steps(draw):
    """The arguments of every setter, inside the ranges or (sometimes) not."""
    w, h = draw(FRAME_SIDE), draw(FRAME_SIDE)
    camera = [draw(FOCAL), draw(FOCAL), draw(CENTRE), draw(CENTRE)]
    distortion = [draw(RADIAL), draw(RADIAL), draw(TANGENTIAL), draw(TANGENTIAL), draw(RADIAL),
                  draw(RADIAL), draw(RADIAL), draw(RADIAL)]
    offset0 = draw(OFFSET)
    offset1 = draw(st.one_of(OFFSET, SPACING.map(lambda d: offset0 + d)))
    return dict(frame=(w, h), camera=camera, distortion=distortion,
                h=[draw(homographies()), draw(homographies())], offsets=(offset0, offset1),
                encoder=draw(ENCODER), grid=(draw(FIRST_X), draw(PITCH), draw(COUNT)))


def synthetic_frame(width, height, rows, dtype, seed):
    """Two bright lines at `rows` (px) over a dim noisy background."""
    rng = np.random.default_rng(seed)
    top = np.iinfo(dtype).max
    v = np.arange(height)[:, None]
    image = 0.03 * top + rng.normal(0, 0.01 * top, (height, width))
    for r in rows:
        image = image + 0.6 * top * np.exp(-0.5 * ((v - r) / 2.0) ** 2)
    return np.clip(image, 0, top).astype(dtype)


def check_extracted(what, row, fibers):
    s, height, slope, valid = row
    assert math.isfinite(s), f"{what}: s = {s}"
    assert height.shape == (fibers,) and slope.shape == (fibers,)
    # extractor.h: NaN where invalid, finite where valid.
    assert np.all(np.isfinite(height[valid])) and np.all(np.isfinite(slope[valid])), what
    assert np.all(np.isnan(height[~valid])) and np.all(np.isnan(slope[~valid])), what


@settings(max_examples=examples(150))
@given(steps=calibration_steps(), seed=st.integers(0, 2**32 - 1),
       extract=options_of(("extract_",)), line_rows=st.tuples(st.floats(0, 1), st.floats(0, 1)),
       bits=st.sampled_from([8, 10, 12, 16]), sim_options=options_of(("sim_",)))
@closing
def test_calibration_setters_loader_and_the_chain(steps, seed, extract, line_rows, bits,
                                                  sim_options):
    calib = flatline.Calibration()
    accepted = []
    for what, fn, args in [
        ("frame_size", setattr, (calib, "frame_size", steps["frame"])),
        ("set_intrinsics", lambda: calib.set_intrinsics(
            flatline.Intrinsics.from_arrays(steps["camera"], steps["distortion"])), ()),
        ("set_homography 0", calib.set_homography, (0, steps["h"][0])),
        ("set_homography 1", calib.set_homography, (1, steps["h"][1])),
        ("set_laser_offset 0", calib.set_laser_offset, (0, steps["offsets"][0])),
        ("set_laser_offset 1", calib.set_laser_offset, (1, steps["offsets"][1])),
        ("encoder_scale", setattr, (calib, "encoder_scale", steps["encoder"])),
        ("fiber_grid", setattr, (calib, "fiber_grid", steps["grid"])),
    ]:
        ok, _ = call(what, fn, *args)
        accepted.append(ok)
        note(f"{what}: {'ok' if ok else 'refused'}")
    ok, error = call("finish", calib.finish)
    if not ok:
        # The model stays unfinished and usable: a setter still works.
        assert isinstance(error, flatline.StateError), error
        call("set_laser_offset", calib.set_laser_offset, 0, -50.0)
        return
    assert all(accepted)
    # A finished model saves and loads to the same text.
    text = calib.dumps()
    again = flatline.Calibration.loads(text)
    assert again.dumps() == text
    # Mapping any point gives a point or NaN, nothing else.
    rng = np.random.default_rng(seed)
    w, h = calib.frame_size
    points = np.column_stack([rng.uniform(-w, 2 * w, 64), rng.uniform(-h, 2 * h, 64)])
    for laser in (0, 1):
        for fn in (calib.image_to_plane, calib.plane_to_image):
            ok, mapped = call("map", fn, laser, points)
            assert ok
            assert not np.any(np.isinf(mapped)), "a mapped point is infinite"
    # The chain: an extractor on a synthetic frame of the model's size.
    if w * h > 4_000_000:
        return
    dtype = np.uint8 if bits == 8 else np.uint16
    ok, ex = call("Extractor", flatline.Extractor, calib, bits, **extract)
    if ok:
        frame = synthetic_frame(w, h, [line_rows[0] * (h - 1), line_rows[1] * (h - 1)], dtype,
                                seed)
        for f in range(2):
            ok, row = call("process", ex.process, frame, 3.0 * f)
            if ok:
                check_extracted("process", row, ex.fibers)
        ok, _ = call("fibers", lambda: ex.fibers)  # usable after any refusal
        assert ok
        ex.close()
    # ... and a simulator drawing through it.
    if w * h > 1_000_000:
        return
    ok, sim = call("SimulatedLine", flatline.SimulatedLine, calib, **sim_options)
    if ok:
        ok, rows = call("next_rows", sim.next_rows, 4, rows=4)
        assert ok
        for name in ("height", "slope", "truth", "s", "encoder_mm"):
            values = getattr(rows, name)
            assert np.all(np.isfinite(values)), f"sim {name} not finite (valid all set)"
        ok, frame = call("next_frame", sim.next_frame)
        assert ok
        sim.close()


# -- simulator and extractor -------------------------------------------------------


@settings(max_examples=examples(60))
@given(sim_options=options_of(("sim_",)), extract=options_of(("extract_",)),
       fibers=st.sampled_from([1, 2, 101, 1001, 4096]),
       pitch=st.sampled_from([1e-3, 0.5, 2.0, 1e4 / 4096]),
       defects=st.lists(st.tuples(st.sampled_from(list(flatline.Defect)),
                                  st.one_of(st.floats(-1e3, 1e3), st.sampled_from(
                                      [0.0, 12.0, 1e6, -1e9, 1e300])),
                                  st.one_of(st.floats(0, 1e4), st.sampled_from(
                                      [0.0, 1800.0, 1e300]))), max_size=3),
       frames=st.integers(1, 3), encoder=st.sampled_from([0.0, -1e9, 1e12, 5e-324]))
@closing
def test_simulated_frames_through_the_extractor(sim_options, extract, fibers, pitch, defects,
                                                frames, encoder):
    first_x = max(-1e5, -0.5 * pitch * (fibers - 1))
    calib = flatline.Calibration.reference(first_row=900, rows=256, first_x_mm=first_x,
                                           pitch_mm=pitch, fibers=fibers)
    ok, sim = call("SimulatedLine", flatline.SimulatedLine, calib, **sim_options)
    if not ok:
        return
    for kind, amplitude, period in defects:
        call("add_defect", sim.add_defect, kind, amplitude, period)
    ok, rows = call("next_rows", sim.next_rows, 3, rows=3)
    assert ok
    # sim.h: a fiber on the strip is valid and its values finite numbers;
    # off the strip (edges, coils: a head not yet under both lasers) its
    # values are NaN with valid False, never a NaN without its flag.
    for name in ("height", "slope", "truth"):
        values = getattr(rows, name)
        assert np.all(np.isfinite(values[rows.valid])), f"sim {name} not finite"
        assert np.all(np.isnan(values[~rows.valid])), f"sim {name} off the strip not NaN"
    ok, ex = call("Extractor", flatline.Extractor, calib, sim.pixel_format, **extract)
    if not ok:
        return
    for f in range(frames):
        ok, frame = call("next_frame", sim.next_frame)
        assert ok
        assert not np.any(np.isinf(frame.truth))  # NaN off the strip only
        ok, row = call("process", ex.process, frame.image, encoder + 3.0 * f)
        if ok:
            check_extracted("process", row, fibers)
        else:  # an automatic band the frame does not show: tried again next frame
            assert isinstance(row, flatline.NumericError), row
    ok, _ = call("band", ex.band, 0)
    sim.close()
    ex.close()


# -- reconstructor -------------------------------------------------------------------

RECON_OPTIONS = tuple(n for n in flatline.reconstructor_options())


def recon_bytes(fibers, o):
    """What recon.h says a reconstructor with these options allocates
    ("Memory"), to keep the suite's draws within a budget."""
    laser = o.get("laser_spacing", 100.0)
    knot = o.get("knot_spacing", 0.0) or laser
    lag = o.get("lag_knots", -1.0)
    if lag < 0:
        # From latency_mm: the longest lag with lag + lag/8 + 2 knots and
        # half the laser spacing within it (a float: knot may be 1e-306);
        # the strip's head waits twice as long.
        lag = max(0.0, ((o.get("latency_mm", 2000.0) - laser / 2) / knot - 2) * 8 / 9)
        wait = 2 * (lag + lag / 8 + 2)
    else:
        wait = lag + lag / 8 + 1
    rows = o.get("row_capacity", 8192.0)
    robust = bool(o.get("robust", 0.0))
    S = float(np.ceil(laser / knot - 1e-9)) + 2
    total = rows * (9 + 9 * fibers)
    if not robust:
        total += fibers * (wait + lag / 8 + 12) * 8 * (4 * S + 3)
    else:
        total += rows * (8 + 8 * fibers)
        total += fibers * 16 * ((2 * S + 1) * (S + 1) * (wait + 2 * S + 8) + wait + lag / 8 + 170)
    if o.get("rigid_motion", 0.0):
        total += rows * (92 if robust else 60)
    return total


BUDGET = 300e6  # bytes per Flatness the suite allows itself (flatness_bytes)
RECON_BUDGET = 100e6  # and per Reconstructor (recon_bytes)


class ReconMachine(RuleBasedStateMachine):
    """Random call sequences on one streaming reconstructor."""

    def __init__(self):
        super().__init__()
        self.recon = None
        self.last_s = None
        self.pushed = False

    @rule(fibers=st.sampled_from([1, 2, 3, 7, 16]),
          options=options_of((), names=RECON_OPTIONS))
    @precondition(lambda self: self.recon is None)
    def create(self, fibers, options):
        assume(recon_bytes(fibers, options) < RECON_BUDGET)
        ok, recon = call("Reconstructor", flatline.Reconstructor, fibers,
                         megabytes=recon_bytes(fibers, options) / 1e6, **options)
        if not ok:  # inconsistent options (knots too fine for the lasers)
            return
        self.recon, self.fibers = recon, fibers
        self.knot = recon.option("knot_spacing")
        self.max_jump = min(1e6, 1000 * self.knot)

    @rule(rows=st.integers(1, 40), seed=st.integers(0, 2**32 - 1),
          kinds=st.tuples(st.integers(0, 3), st.integers(0, 3), st.integers(0, 3)),
          scales=st.tuples(SCALES, SCALES), masked=st.booleans(),
          start=st.sampled_from([0.0, -1e9, 1e9, 1e12]),
          disorder=st.sampled_from([None, None, None, "repeat", "nan", "jump"]))
    @precondition(lambda self: self.recon is not None)
    def push(self, rows, seed, kinds, scales, masked, start, disorder):
        rng = np.random.default_rng(seed)
        first = start if self.last_s is None else self.last_s
        s = positions(rng, first, rows, kinds[0], self.max_jump)
        if disorder == "repeat" and rows > 1:
            s[-1] = s[-2]
        elif disorder == "nan":
            s[rng.integers(rows)] = math.nan
        elif disorder == "jump":
            s[-1] = s[-2 if rows > 1 else -1] + 2 * self.max_jump + 1
        height = block(rng, kinds[1], rows, self.fibers, scales[0])
        slope = block(rng, kinds[2], rows, self.fibers, scales[1] * 1e-3)
        valid = rng.random((rows, self.fibers)) > 0.1 if masked else None
        # Positions the header refuses: not finite, not increasing, or
        # jumping more than the limit past the previous row.
        refuse = (disorder == "nan" or (disorder == "repeat" and rows > 1) or
                  (disorder == "jump" and (rows > 1 or self.last_s is not None)))
        ready = self.recon.ready
        ok, error = call("push", self.recon.push, s, height, slope, valid, rows=rows)
        if ok:
            assert not refuse, f"push took positions {s}"
            self.last_s = float(s[-1])
            self.pushed = True
        else:
            # recon.h: on failure nothing was pushed.
            assert self.recon.ready == ready
            assert isinstance(error, (flatline.InvalidArgumentError,
                                      flatline.BufferFullError)), error

    @rule(max_rows=st.one_of(st.none(), st.integers(0, 50), st.just(2**62)))
    @precondition(lambda self: self.recon is not None)
    def pull(self, max_rows):
        ready = self.recon.ready
        ok, out = call("pull", self.recon.pull, max_rows, rows=max(1, ready))
        if not self.pushed:
            assert not ok and isinstance(out, flatline.StateError)
            return
        assert ok
        s, z, flags = out
        assert len(s) == (ready if max_rows is None else min(ready, max_rows))
        assert np.all(np.isfinite(s)) and np.all(np.diff(s) > 0)
        assert_nan_flagged("pull", z, flags, NAN_FLAGS)

    @rule()
    @precondition(lambda self: self.recon is not None)
    def end_sheet(self):
        ok, error = call("end_sheet", self.recon.end_sheet, rows=1000)
        if not ok:
            assert isinstance(error, flatline.StateError), error

    @rule()
    @precondition(lambda self: self.recon is not None)
    def reset(self):
        ok, _ = call("reset", self.recon.reset)
        assert ok
        self.last_s, self.pushed = None, False

    @rule()
    @precondition(lambda self: self.recon is not None)
    def boundary(self):
        ok, out = call("boundary", self.recon.boundary)
        if ok:
            s, height, slope = out
            assert math.isfinite(s)

    @invariant()
    def usable(self):
        if self.recon is not None:
            assert self.recon.ready >= 0

    def teardown(self):
        if self.recon is not None:
            self.recon.close()
        trim_heap()


TestReconstructorSequences = ReconMachine.TestCase
TestReconstructorSequences.settings = settings(max_examples=examples(80),
                                               stateful_step_count=20)


@settings(max_examples=examples(150))
# The largest sheet the suite allows itself (BUDGET, as batch_bytes below
# counts it: 90 rows 100 m apart, 90,005 knots x 24 fibers, 294 MB), at every
# scale: the test's peak memory is this one example's, the same at scale 1
# and 3 (the working memory of each call is freed after it).
@example(fibers=24, options={}, rows=90, seed=1, kinds=(3, 0, 0), scales=(1.0, 1.0),
         masked=False, start=0.0)
@given(fibers=st.sampled_from([1, 2, 5, 24]), options=options_of((), names=RECON_OPTIONS),
       rows=st.integers(1, 300), seed=st.integers(0, 2**32 - 1),
       kinds=st.tuples(st.integers(0, 3), st.integers(0, 3), st.integers(0, 3)),
       scales=st.tuples(SCALES, SCALES), masked=st.booleans(),
       start=st.sampled_from([0.0, -1e9, 1e12]))
@closing
def test_batch_reconstruction(fibers, options, rows, seed, kinds, scales, masked, start):
    assume(recon_bytes(fibers, options) < RECON_BUDGET)
    rng = np.random.default_rng(seed)
    laser = options.get("laser_spacing", 100.0)
    knot = options.get("knot_spacing", 0.0) or laser
    s = positions(rng, start, rows, kinds[0], min(1e6, 1000 * knot))
    # The whole sheet's knots are allocated at once: skip sheets between the
    # suite's budget and FLT_RECON_MAX_BYTES (above it they must be refused).
    knots = (s[-1] - s[0] + laser) / knot + 4
    per_knot = 5 + 2 * (2 * (float(np.ceil(laser / knot)) + 2) - 2) + 4
    batch_bytes = knots * fibers * per_knot * 8 * (2 if options.get("robust") else 1)
    assume(batch_bytes < BUDGET or batch_bytes > 3e9)
    height = block(rng, kinds[1], rows, fibers, scales[0])
    slope = block(rng, kinds[2], rows, fibers, scales[1] * 1e-3)
    valid = rng.random((rows, fibers)) > 0.1 if masked else None
    try:
        ok, out = call("reconstruct", flatline.reconstruct_with_flags, s, height, slope, valid,
                       rows=rows, **options)
    finally:
        # The working memory the call kept for its shape: freed, so the
        # suite's peak is each example's own, not that of the largest shapes
        # drawn so far (more of them at a larger scale).
        flatline.release_reconstruct_memory()
    if not ok:
        assert isinstance(out, flatline.InvalidArgumentError), out
        return
    z, flags = out
    assert_nan_flagged("reconstruct", z, flags, NAN_FLAGS)


# -- flatness --------------------------------------------------------------------------

FLAT_OPTIONS = tuple(n for n in OPTIONS if n.startswith("flat_"))


def flatness_bytes(fibers, options):
    """What flatness.h says a Flatness allocates ("Memory"): per row of
    flat_row_capacity 97 + 18 bytes per fiber, per fiber about 600 bytes
    (the zones, at most one per fiber here, are in that)."""
    rows = options.get("flat_row_capacity", 4096.0)
    return rows * (97 + 18 * fibers) + 600 * fibers + 4096


@st.composite
def fiber_positions(draw):
    fibers = draw(st.sampled_from([1, 2, 3, 7, 40, 200]))  # 200: at most 20 rows
    first = draw(st.sampled_from([-1e5, -1000.0, 0.0]))
    pitch = draw(st.sampled_from([1e-3, 2.0, 37.5, 1e4]))
    x = first + pitch * np.arange(fibers)
    if draw(st.booleans()):  # jittered, still increasing
        seed = draw(st.integers(0, 2**32 - 1))
        x = x + np.random.default_rng(seed).uniform(0, 0.4 * pitch, fibers)
    return x


def check_flatness_result(what, result):
    fiber, zone, shape = result.fibers, result.zones, result.shape
    no_data = (fiber.flags & flatline.FIBER_NO_DATA) != 0
    no_wave = no_data | ((fiber.flags & flatline.FIBER_NO_WAVE) != 0)
    for name, values, allowed in [("arc_length", fiber.arc_length, no_data),
                                  ("i_units", fiber.i_units, no_data),
                                  ("wave_height", fiber.wave_height, no_wave),
                                  ("wave_period", fiber.wave_period, no_wave),
                                  ("steepness", fiber.steepness_percent, no_wave)]:
        bad = ~np.isfinite(values) & ~allowed
        assert not bad.any(), f"{what}: fiber {name} {values[bad][:3]} without its flag"
    bad = ~np.isfinite(zone.i_units) & ((zone.flags & flatline.ZONE_NO_DATA) == 0)
    assert not bad.any(), f"{what}: zone I-Units {zone.i_units[bad][:3]} without the flag"
    window = result.window.flags
    assert math.isfinite(shape.confidence) and 0 <= shape.confidence <= 1, what
    assert math.isfinite(shape.bow_mm) or window & flatline.WINDOW_NO_BOW, what
    assert math.isfinite(shape.crossbow_mm) or window & flatline.WINDOW_NO_CROSSBOW, what


@settings(max_examples=examples(100))
# Found by the suite, kept as fixed cases: a shape confidence that rounded
# to 1.0000000000000002.
@example(x=-1e5 + 2.0 * np.arange(200), options={}, rows=20, seed=116, kinds=(2, 3), scale=1e-3,
         flagged=False, chunk=1)
# The largest Flatness the suite allows itself (BUDGET), at every scale: the
# suite's peak memory is this one example's, the same at scale 1 and 3.
@example(x=np.array([0.0]), options={"flat_row_capacity": 2.5e6}, rows=200, seed=1,
         kinds=(1, 1), scale=1.0, flagged=True, chunk=50)
@given(x=fiber_positions(), options=options_of((), names=FLAT_OPTIONS),
       rows=st.integers(1, 200), seed=st.integers(0, 2**32 - 1),
       kinds=st.tuples(st.integers(0, 3), st.integers(0, 3)), scale=SCALES,
       flagged=st.booleans(), chunk=st.sampled_from([1, 7, 50, 200]))
@closing
def test_flatness_whole_sheets_and_streams(x, options, rows, seed, kinds, scale, flagged,
                                           chunk):
    fibers = len(x)
    # A window may be evaluated at every row pushed (flat_update_interval
    # at its minimum): keep rows x fibers small enough for the suite's time.
    rows = min(rows, 20) if fibers > 40 else rows
    # The buffers flatness.h documents; above FLT_FLATNESS_MAX_BYTES the
    # library must refuse before allocating, so those draws stay.
    bytes_ = flatness_bytes(fibers, options)
    refused = bytes_ > capi.FLT_FLATNESS_MAX_BYTES * 1.01
    assume(bytes_ < BUDGET or refused)
    ok, flat = call("Flatness", flatline.Flatness, x, megabytes=bytes_ / 1e6, **options)
    if not ok:  # too many zones for the grid, or inconsistent windows
        assert isinstance(flat, flatline.InvalidArgumentError), flat
        return
    assert not refused, f"a Flatness of about {bytes_ / 1e9:.2f} GB was made"
    assert 1 <= flat.zones <= capi.FLT_FLATNESS_MAX_ZONES
    rng = np.random.default_rng(seed)
    s = positions(rng, 0.0, rows, kinds[0], 1e4)
    z = block(rng, kinds[1], rows, fibers, scale)
    flags = rng.choice(np.array([0, 1, 2, 4], dtype=np.uint8), size=(rows, fibers),
                       p=[0.85, 0.05, 0.05, 0.05]) if flagged else None
    ok, result = call("evaluate", flat.evaluate, s, z, flags, rows=rows)
    if ok:
        check_flatness_result("evaluate", result)
    else:
        assert isinstance(result, flatline.InvalidArgumentError), result
    # The same rows streamed in chunks, then finish.
    start = 0
    while start < rows:
        part = slice(start, min(rows, start + chunk))
        ok, out = call("push", flat.push, s[part], z[part],
                       None if flags is None else flags[part], rows=part.stop - part.start)
        if not ok:
            assert isinstance(out, flatline.BufferFullError), out
            call("reset", flat.reset)
            break
        consumed, evaluated = out
        if evaluated:
            ok, result = call("result", flat.result)
            assert ok
            check_flatness_result("push", result)
        assert consumed > 0 or evaluated
        start += consumed
    ok, result = call("finish", flat.finish, rows=rows)
    assert ok
    if result is not None:
        check_flatness_result("finish", result)
    flat.close()


# -- frame source over the simulator --------------------------------------------------


@settings(max_examples=examples(40))
@given(options=options_of(("source_encoder",)),
       calls=st.lists(st.sampled_from(["start", "stop", "next", "encoder"]), max_size=12),
       encoder=st.one_of(st.floats(-1e12, 1e12), st.sampled_from([math.nan, math.inf])))
@closing
def test_simulator_source_call_sequences(options, calls, encoder):
    calib = flatline.Calibration.reference(first_row=900, rows=64, fibers=11)
    sim = flatline.SimulatedLine(calib)
    ok, source = call("Source.simulator", flatline.Source.simulator, sim, **options)
    if not ok:
        return
    started = False
    for what in calls:
        if what == "start":
            ok, error = call("start", source.start)
            assert ok != started, error  # StateError when started
            started = True
        elif what == "stop":
            ok, _ = call("stop", source.stop)
            assert ok
            started = False
        elif what == "next":
            ok, frame = call("next", source.next, 100)
            if ok:
                assert started
                assert frame.pixels.shape == (64, 2048)
                assert math.isfinite(frame.encoder_mm)
            elif not started:
                assert isinstance(frame, flatline.StateError), frame
        else:
            call("set_encoder", source.set_encoder, encoder)
    source.close()
    sim.close()
