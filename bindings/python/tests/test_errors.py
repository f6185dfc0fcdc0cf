# SPDX-License-Identifier: Apache-2.0
"""Every C status maps to its exception class, and every status Python can
trigger is raised by the real C path with the library's message."""

import builtins

import numpy as np
import pytest

import flatline
from flatline import capi
from flatline._errors import _BY_STATUS, _from_status

from conftest import sine_sheet

MAPPING = [
    (capi.FLT_ERR_INVALID_ARGUMENT, flatline.InvalidArgumentError, ValueError),
    (capi.FLT_ERR_OUT_OF_MEMORY, flatline.OutOfMemoryError, MemoryError),
    (capi.FLT_ERR_STATE, flatline.StateError, RuntimeError),
    (capi.FLT_ERR_BUFFER_FULL, flatline.BufferFullError, RuntimeError),
    (capi.FLT_ERR_IO, flatline.FileError, OSError),
    (capi.FLT_ERR_FORMAT, flatline.FormatError, ValueError),
    (capi.FLT_ERR_DEVICE, flatline.DeviceError, OSError),
    (capi.FLT_ERR_TIMEOUT, flatline.TimeoutError, builtins.TimeoutError),
    (capi.FLT_ERR_NOT_FOUND, flatline.NotFoundError, KeyError),
    (capi.FLT_ERR_NUMERIC, flatline.NumericError, ArithmeticError),
    (capi.FLT_ERR_INTERNAL, flatline.InternalError, RuntimeError),
]


@pytest.mark.parametrize("status, cls, builtin", MAPPING)
def test_each_status_maps_to_its_class(status, cls, builtin):
    exc = _from_status(status, "why it failed")
    assert type(exc) is cls
    assert isinstance(exc, flatline.FlatlineError) and isinstance(exc, builtin)
    assert exc.status == status == cls.STATUS
    assert exc.message == str(exc) == "why it failed"
    # The C name of the status agrees with the class.
    assert capi.flt_status_string(status).startswith("FLT_ERR_")


def test_mapping_covers_every_status_of_the_header():
    statuses = {v for k, v in vars(capi).items() if k.startswith("FLT_ERR_")}
    assert statuses == {status for status, _, _ in MAPPING}


def test_unknown_status_gives_the_base_class():
    exc = _from_status(-1234, "future code")
    assert type(exc) is flatline.FlatlineError and exc.status == -1234


def test_errors_pickle_with_their_status():
    import pickle
    exc = pickle.loads(pickle.dumps(_from_status(-9, "gone")))
    assert type(exc) is flatline.NotFoundError and exc.status == -9 and exc.message == "gone"


def test_errors_name_the_public_module():
    # what a traceback prints: "flatline.FileError: ...", where users import it
    import traceback
    with pytest.raises(flatline.FileError) as e:
        flatline.Calibration.load("/nonexistent/sensor.json")
    assert type(e.value).__module__ == "flatline"
    assert "flatline.FileError: " in "".join(traceback.format_exception_only(e.type, e.value))
    for status, cls in _BY_STATUS.items():
        assert getattr(flatline, cls.__name__) is cls, cls


# --- raised through the extension ------------------------------------------


def test_invalid_argument_from_c_names_the_argument_and_value():
    s, h, sl, _ = sine_sheet(fibers=2, length=600)
    s = s.copy()
    s[10] = s[9]  # not strictly increasing
    with pytest.raises(flatline.InvalidArgumentError) as info:
        flatline.reconstruct(s, h, sl)
    assert info.value.status == -1
    assert "s[10]" in info.value.message and "increasing" in info.value.message
    assert isinstance(info.value, ValueError)
    # The thread's C error state agrees with what was raised.
    assert capi.flt_last_error_status() == -1


def test_option_out_of_bounds_is_invalid_argument_naming_it():
    with pytest.raises(flatline.InvalidArgumentError, match="row_capacity' = 4 is outside"):
        flatline.Reconstructor(2, row_capacity=4)
    with pytest.raises(ValueError, match="laser_spacing' is NaN"):
        flatline.reconstruct([0.0, 1.0], np.zeros((2, 1)), np.zeros((2, 1)),
                             laser_spacing=float("nan"))


def test_state_errors_pull_before_push_and_end_sheet_twice():
    with flatline.Reconstructor(3) as recon:
        with pytest.raises(flatline.StateError, match="nothing was pushed") as info:
            recon.pull()
        assert info.value.status == -3
        with pytest.raises(flatline.StateError):
            recon.end_sheet()
        with pytest.raises(flatline.StateError, match="no sheet has ended"):
            recon.boundary()
        s, h, sl, _ = sine_sheet(fibers=3, length=900)
        recon.push(s, h, sl)
        recon.end_sheet()
        with pytest.raises(flatline.StateError, match="no row was pushed since the last end_sheet"):
            recon.end_sheet()


def test_buffer_full_with_small_row_capacity_pushes_nothing():
    s, h, sl, _ = sine_sheet(fibers=2, length=300)  # 100 rows
    with flatline.Reconstructor(2, row_capacity=16) as recon:
        with pytest.raises(flatline.BufferFullError, match="row_capacity = 16") as info:
            recon.push(s[:17], h[:17], sl[:17])
        assert info.value.status == -4
        recon.push(s[:16], h[:16], sl[:16])  # nothing of the failed block went in
        assert recon.ready == 0


def test_not_found_for_an_unknown_option_name():
    with pytest.raises(flatline.NotFoundError, match="no option is named 'nope'") as info:
        flatline.option_info("nope")
    assert info.value.status == -9 and isinstance(info.value, LookupError)
    with flatline.Reconstructor(1) as recon, pytest.raises(KeyError):
        recon.option("nope")
    with pytest.raises(flatline.NotFoundError):
        capi.flt_option_at(10**6)


def test_out_of_memory_status_is_a_memory_error():
    # The library refuses sizes beyond its documented limits before
    # allocating (FLT_RECON_MAX_BYTES), so no call of the public API can be
    # made to run out of memory on purpose; the mapping is checked directly.
    error = _from_status(-2, "flt_x: out of memory")
    assert isinstance(error, flatline.OutOfMemoryError) and isinstance(error, MemoryError)
    assert error.status == -2 and str(error) == "flt_x: out of memory"


def test_buffers_beyond_the_memory_limit_are_refused_before_allocating():
    # 10^8 rows of 16384 fibers: 14.7 TB of row ring, refused with the
    # estimate in the message (not an allocation attempt).
    with pytest.raises(flatline.InvalidArgumentError, match="GB, more than 2.15 GB"):
        flatline.Reconstructor(16384, row_capacity=10**8)


def test_too_many_fibers_is_refused_naming_the_limit():
    with pytest.raises(flatline.InvalidArgumentError, match="'fibers' = 2147483648 is too large"):
        flatline.Reconstructor(2**31, row_capacity=16)


def test_integers_out_of_range_are_value_errors_not_overflow_errors():
    # SWIG's conversions raised OverflowError for an int outside the C type
    # (flatline.Reconstructor(2**64)); every out-of-range value is a
    # ValueError (InvalidArgumentError from the binding's typemaps), naming
    # the function, the argument and the value.
    with pytest.raises(flatline.InvalidArgumentError,
                       match=r"flt_recon_create: argument 'fibers' = 18446744073709551616 is outside"):
        flatline.Reconstructor(2**64)
    cases = [
        lambda: capi.flt_recon_create(-1, None),             # size_t, negative
        lambda: capi.flt_recon_create(2**64 + 5, None),      # size_t, too large
        lambda: capi.flt_option_info(2**31),                 # an enum (int-sized)
        lambda: capi.flt_options_set(capi.flt_options_create(), -2**40, 1.0),
        lambda: capi.flt_calib_create_reference(2**32, 2, -1000.0, 2.0, 11),  # uint32_t
        lambda: capi.flt_calib_get_laser_offset(flatline.Calibration.reference()._live(), 2**33),
        lambda: capi.flt_options_set(capi.flt_options_create(), 100, 10**400),  # a double
    ]
    for case in cases:
        with pytest.raises(ValueError) as info:
            case()
        assert isinstance(info.value, flatline.InvalidArgumentError), info.value
        assert "is outside" in str(info.value)
    # The Python layer's own conversions: options and real arguments.
    with pytest.raises(flatline.InvalidArgumentError, match="'row_capacity' = 1000000"):
        flatline.Reconstructor(3, row_capacity=10**400)
    with pytest.raises(ValueError, match="'pitch_mm' = 1000000.*range of a double"):
        flatline.Calibration.reference(pitch_mm=10**400)
    # Not an integer at all is still a TypeError.
    with pytest.raises(TypeError, match="must be an integer, not float"):
        capi.flt_recon_create(1.5, None)


def test_unknown_keyword_is_a_type_error_naming_it():
    with pytest.raises(TypeError, match="unexpected keyword argument 'knot_spcing'"):
        flatline.reconstruct([0.0, 3.0], np.zeros((2, 1)), np.zeros((2, 1)), knot_spcing=50)
    # a typo gets the closest name, a name like none gets none
    with pytest.raises(TypeError, match="did you mean 'rigid_motion'\\?"):
        flatline.Reconstructor(1, rigid_motoin=1)
    with pytest.raises(TypeError) as e:
        flatline.Reconstructor(1, banana=1)
    assert "did you mean" not in str(e.value)
    with pytest.raises(TypeError, match="'robustt'"):
        flatline.Reconstructor(1, robustt=1)


def test_option_of_wrong_type_is_a_type_error():
    with pytest.raises(TypeError, match="'lag_knots' must be a real number, not str"):
        flatline.Reconstructor(1, lag_knots="8")
    with pytest.raises(TypeError, match="not bool"):
        flatline.Reconstructor(1, lag_knots=True)


def test_a_choice_takes_its_name_and_a_switch_takes_a_bool():
    """robust="huber" is robust=1; robust=True the recommended mode (Huber,
    the first after "none"); rigid_motion=True is 1. A name that is not a
    choice is a ValueError listing them; a bool where neither makes sense is
    still a TypeError."""
    with flatline.Reconstructor(1, robust="tukey", rigid_motion=True) as recon:
        assert recon.option("robust") == 2.0 and recon.option("rigid_motion") == 1.0
    with flatline.Reconstructor(1, robust=True) as recon:
        assert recon.option("robust") == float(capi.FLT_ROBUST_HUBER)
    with flatline.Reconstructor(1, robust=False, rigid_motion=False) as recon:
        assert recon.option("robust") == 0.0 and recon.option("rigid_motion") == 0.0
    with flatline.Reconstructor(1, robust=1) as recon:  # numbers still work
        assert recon.option("robust") == 1.0
    with pytest.raises(ValueError, match="'robust' = 'hubert' is not one of 'none', 'huber', "
                                         "'tukey'"):
        flatline.Reconstructor(1, robust="hubert")
    with pytest.raises(TypeError, match="'lag_knots' must be a real number, not str"):
        flatline.Reconstructor(1, lag_knots="huber")
    with pytest.raises(TypeError, match="'flat_reference' must be a real number or one of "
                                        "'shortest', 'mean', not bool"):
        flatline.Flatness([0.0, 1.0], flat_reference=True)
    with flatline.Flatness([0.0, 10.0, 20.0], flat_reference="mean") as flat:
        assert flat is not None
    info = flatline.option_info("source_encoder_mode")
    assert dict(info.choices) == {"auto": 0, "fixed_step": 1, "host": 2, "chunk": 3}
    assert flatline.option_info("rigid_motion").is_switch
    assert not flatline.option_info("max_gap").choices
    assert "robust (str or int): one of 'none', 'huber', 'tukey'; default 'none'" in \
        flatline.Reconstructor.__doc__
    assert "rigid_motion (bool): default False" in flatline.Reconstructor.__doc__


def test_an_option_of_another_component_is_an_unexpected_keyword():
    """Python names it as it does any unexpected keyword; the C library
    refuses it too (InvalidArgumentError), for a bag made by hand."""
    with pytest.raises(TypeError, match="unexpected keyword argument 'sim_seed' "
                                        r"\(an option of another component"):
        flatline.Reconstructor(2, sim_seed=3)
    with pytest.raises(TypeError, match="unexpected keyword argument 'robust'"):
        flatline.Flatness([0.0, 1.0], robust="huber")
    bag = capi.flt_options_create()
    capi.flt_options_set(bag, capi.FLT_OPT_SIM_SEED, 3.0)
    with pytest.raises(flatline.InvalidArgumentError,
                       match="'sim_seed' belongs to the simulator, not to the reconstructor"):
        capi.flt_recon_create(2, bag)
    with flatline.Reconstructor(1) as recon, \
            pytest.raises(flatline.InvalidArgumentError, match="belongs to the simulator"):
        recon.option("sim_seed")
    # An unknown key: NotFoundError from set, get and info alike.
    for call in (lambda: capi.flt_options_set(bag, 99, 1.0),
                 lambda: capi.flt_options_get(bag, 99),
                 lambda: capi.flt_option_info(99)):
        with pytest.raises(flatline.NotFoundError, match="unknown option key 99"):
            call()


def test_a_failed_call_leaves_the_reconstructor_usable():
    s, h, sl, _ = sine_sheet(fibers=2, length=900)
    with flatline.Reconstructor(2, lag_knots=4) as recon:
        recon.push(s[:100], h[:100], sl[:100])
        with pytest.raises(flatline.InvalidArgumentError):
            recon.push(s[:10], h[:10], sl[:10])  # goes backwards
        recon.push(s[100:], h[100:], sl[100:])
        recon.end_sheet()
        out_s, z, flags = recon.pull()
    np.testing.assert_array_equal(out_s, s)
    assert not flags.any()
