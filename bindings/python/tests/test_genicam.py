# SPDX-License-Identifier: Apache-2.0
"""The offline view of a camera description (flatline.genicam): a small
description written here, evaluated against register bytes the test puts
into the memory image (values worked out by hand), a zipped copy, errors,
and the real descriptions of FLT_EXTERNAL_DATA when present."""

import io
import os
import struct
import zipfile

import pytest

import flatline
from flatline.genicam import Access, CameraDescription, EnumEntry, FeatureType, Register

XML = b"""<?xml version="1.0" encoding="utf-8"?>
<RegisterDescription VendorName="Flatline" ModelName="PyCam" SchemaMajorVersion="1"
    SchemaMinorVersion="1" SchemaSubMinorVersion="0">
  <Category Name="Root"><pFeature>ImageFormat</pFeature><pFeature>Label</pFeature>
    <pFeature>Ghost</pFeature><pFeature>Loop</pFeature></Category>
  <Category Name="ImageFormat"><pFeature>Width</pFeature><pFeature>ExposureTime</pFeature>
  </Category>
  <Category Name="Loop"><pFeature>Loop</pFeature></Category>
  <Category Name="Empty"></Category>
  <Integer Name="Width"><pValue>WidthReg</pValue><Min>16</Min><Max>4096</Max><Inc>16</Inc></Integer>
  <IntReg Name="WidthReg"><Address>0x100</Address><Length>4</Length><AccessMode>RW</AccessMode>
    <pPort>Device</pPort><Sign>Unsigned</Sign><Endianess>BigEndian</Endianess></IntReg>
  <Converter Name="ExposureTime"><FormulaTo>FROM * 2</FormulaTo><FormulaFrom>TO / 2</FormulaFrom>
    <pValue>ExposureRaw</pValue><Unit>us</Unit></Converter>
  <IntReg Name="ExposureRaw"><Address>0x104</Address><Length>4</Length><AccessMode>RW</AccessMode>
    <pPort>Device</pPort><Sign>Unsigned</Sign><Endianess>BigEndian</Endianess></IntReg>
  <Enumeration Name="TriggerMode"><EnumEntry Name="Off"><Value>0</Value></EnumEntry>
    <EnumEntry Name="On"><Value>1</Value><pIsAvailable>Zero</pIsAvailable></EnumEntry>
    <pValue>TriggerReg</pValue></Enumeration>
  <MaskedIntReg Name="TriggerReg"><Address>0x108</Address><Length>4</Length>
    <AccessMode>RW</AccessMode><pPort>Device</pPort><LSB>31</LSB><MSB>31</MSB>
    <Endianess>BigEndian</Endianess></MaskedIntReg>
  <Integer Name="Zero"><Value>0</Value></Integer>
  <Boolean Name="ReverseX"><pValue>TriggerReg</pValue></Boolean>
  <Command Name="AcquisitionStart"><pValue>StartReg</pValue><CommandValue>1</CommandValue></Command>
  <IntReg Name="StartReg"><Address>0x10C</Address><Length>4</Length><AccessMode>WO</AccessMode>
    <pPort>Device</pPort><Endianess>BigEndian</Endianess></IntReg>
  <String Name="Label"><Value>line 1</Value></String>
  <SwissKnife Name="Area"><pVariable Name="W">Width</pVariable><Formula>W * W / 4</Formula>
  </SwissKnife>
</RegisterDescription>
"""


@pytest.fixture
def camera():
    c = CameraDescription(XML)
    c.set_memory(0x100, struct.pack(">I", 640))  # Width 640, big endian
    c.set_memory(0x104, struct.pack(">I", 1000))
    c.set_memory(0x108, struct.pack(">I", 0))
    return c


def test_lists_the_features(camera):
    assert (camera.vendor, camera.model, camera.schema_version) == ("Flatline", "PyCam", "1.1.0")
    assert len(camera) == 12 and "Width" in camera and "Nope" not in camera
    features = {f.name: f for f in camera.features()}
    assert features["ExposureTime"].type == FeatureType.FLOAT
    assert (features["ExposureTime"].kind, features["ExposureTime"].unit) == ("Converter", "us")
    assert features["TriggerMode"].type == FeatureType.ENUMERATION
    assert features["AcquisitionStart"].type == FeatureType.COMMAND
    assert features["Label"].type == FeatureType.STRING
    assert list(camera)[0] == "Width"


def test_feature_tree(camera):
    # the file's order; "Ghost" names no node; "Loop" lists itself (the
    # walk enters it once)
    assert camera.category() == ["ImageFormat", "Label", "Ghost", "Loop"]
    assert camera.category("ImageFormat") == ["Width", "ExposureTime"]
    assert camera.category("Empty") == []
    assert camera.feature("ImageFormat").type == FeatureType.CATEGORY
    assert list(camera.tree()) == [(0, "ImageFormat"), (1, "Width"), (1, "ExposureTime"),
                                   (0, "Label"), (0, "Ghost"), (0, "Loop"), (1, "Loop")]
    with pytest.raises(flatline.NotFoundError, match="no category"):
        camera.category("Width")
    with pytest.raises(flatline.NotFoundError, match="no category"):
        camera.category("Nope")
    # categories are not features
    assert "ImageFormat" not in camera and len(camera) == 12


def test_values_registers_and_bounds(camera):
    assert camera.get("Width") == 640
    assert camera.get("ExposureTime") == 500.0  # 1000 / 2, exact
    assert camera.get("Area") == 640 * 640 / 4
    assert camera.get("TriggerMode") == "Off"
    assert camera.get("ReverseX") is False
    assert camera.get("Label") == "line 1"
    # the converter's register; big-endian bit 31 is the value's bit 0
    assert camera.register("ExposureTime") == Register(0x104, 4, 0, 31, True)
    assert camera.register("TriggerMode") == Register(0x108, 4, 0, 0, True)
    assert camera.int_bounds("Width") == (16, 4096, 16)
    lo, hi = camera.float_bounds("ExposureTime")
    assert (lo, hi) == (0.0, (2**32 - 1) / 2)
    assert camera.entries("TriggerMode") == [EnumEntry("Off", 0, True), EnumEntry("On", 1, False)]
    assert camera.access("Width") == Access.READ_WRITE
    assert camera.access("AcquisitionStart") == Access.WRITE_ONLY
    assert camera.access("Area") == Access.READ_ONLY
    assert camera.flags("Width") == (True, True, False)


def test_writes_land_in_the_memory_image(camera):
    camera.set("Width", 800)
    assert camera.get_memory(0x100, 4) == struct.pack(">I", 800)
    camera.set("ExposureTime", 250.0)  # FROM * 2
    assert camera.get_memory(0x104, 4) == struct.pack(">I", 500)
    camera.set("ReverseX", True)
    assert camera.get_memory(0x108, 4) == struct.pack(">I", 1)  # bit 31 big endian: the low bit
    camera.execute("AcquisitionStart")
    assert camera.get_memory(0x10C, 4) == struct.pack(">I", 1)
    camera.clear_memory()
    with pytest.raises(flatline.NotFoundError, match="memory image"):
        camera.get("Width")


def test_errors_name_the_problem(camera):
    with pytest.raises(flatline.InvalidArgumentError, match="outside 16 .. 4096"):
        camera.set("Width", 8192)
    with pytest.raises(flatline.InvalidArgumentError, match="multiple of 16"):
        camera.set("Width", 650)
    with pytest.raises(flatline.StateError, match="not available"):
        camera.set("TriggerMode", "On")
    with pytest.raises(flatline.StateError, match="read-only"):
        camera.set("Area", 1.0)
    with pytest.raises(flatline.NotFoundError, match="'Nope'"):
        camera.get("Nope")
    with pytest.raises(flatline.NotFoundError, match="no single register"):
        camera.register("Area")
    with pytest.raises(TypeError, match="'feature' must be a str"):
        camera.get_int(3)
    with pytest.raises(TypeError, match="bytes-like"):
        camera.set_memory(0, [1, 2])
    with pytest.raises(ValueError, match="address"):
        camera.set_memory(-1, b"\0")
    with pytest.raises(flatline.InvalidArgumentError, match="'count' = 0"):
        camera.get_memory(0x100, 0)
    with pytest.raises(flatline.FormatError, match="malformed"):
        CameraDescription(XML[:200])
    with pytest.raises(flatline.FileError, match="cannot open"):
        CameraDescription("/nonexistent/camera.xml")
    with pytest.raises(TypeError, match="path or bytes"):
        CameraDescription(42)
    camera.set("Width", 32)  # the handle stays usable
    assert camera.get("Width") == 32


def test_zipped_file_and_header_line(tmp_path):
    archive = io.BytesIO()
    with zipfile.ZipFile(archive, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("camera.xml", b"Vendor-0123 (USB3)\r\n" + XML)
    path = tmp_path / "camera.zip"
    path.write_bytes(archive.getvalue())
    c = CameraDescription(path)
    assert c.model == "PyCam" and len(c) == 12


def test_real_descriptions_load():
    root = os.environ.get("FLT_EXTERNAL_DATA")
    folder = os.path.join(root or "", "genicam", "adgenicam_xml")
    if not root or not os.path.isdir(folder):
        pytest.skip("FLT_EXTERNAL_DATA does not hold genicam/adgenicam_xml")
    files = sorted(f for f in os.listdir(folder) if f.endswith(".xml"))
    assert len(files) == 14
    for name in files:
        c = CameraDescription(os.path.join(folder, name))
        assert "Width" in c and c.feature("Width").type == FeatureType.INTEGER
        c.set_memory(0, bytes(1))  # not Width's register: still missing
        with pytest.raises((flatline.NotFoundError, flatline.FormatError)):
            c.get("Width")
