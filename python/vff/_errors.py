"""The vff.Error hierarchy: every libvff error, with its code, name, section and offset.

The classes follow the groups of vff::Code (spec/validation.md): an error of a file's content is an
InvalidFileError whose ``validation_id`` is the rule's ID; I/O errors are also OSError; bad
arguments are also ValueError.
"""


class Error(Exception):
    """A libvff error.

    Attributes:
        code: the numeric vff::Code (for file problems, the validation ID of spec/validation.md).
        name: its kebab-case name ("header-checksum").
        section: the FourCC of the section concerned ("DIST"), or None.
        offset: the absolute byte offset in the file, or None.
        message: one sentence.
    """

    def __init__(self, code, name, section, offset, message):
        self.code = code
        self.name = name
        self.section = section
        self.offset = offset
        self.message = message
        place = ""
        if offset is not None:
            place += "@0x%x " % offset
        if section is not None:
            place += "[%s] " % section
        super().__init__("%s%s (%d): %s" % (place, name, code, message))

    @property
    def validation_id(self):
        """The validation ID (spec/validation.md) for a problem of a file's content, else None."""
        return self.code if 2000 <= self.code < 9000 else None


class IoError(Error, OSError):
    """A file cannot be opened, read or written (codes 1xxx)."""


class InvalidFileError(Error):
    """The file is not a valid .vff (codes 2xxx..8xxx, the validation IDs)."""


class MeshError(Error):
    """A mesh cannot be baked (codes 10xxx)."""


class SceneError(Error):
    """A scene description breaks a rule of spec/scene.md section 5 (codes 11xxx; ``code`` is the ID)."""


class InvalidArgumentError(Error, ValueError):
    """An argument is invalid or out of range (9001, 9002)."""


class UnsupportedError(Error):
    """A valid request this build or this field does not support (9005)."""


class OperationError(Error, RuntimeError):
    """Any other failure (9003 bad state or cancelled, 9004 out of memory)."""


class GltfError(Error):
    """A field of a glTF asset that may not be used (the extension VFF_visibility_field,
    spec/gltf/VFF_visibility_field/README.md): ``code`` is the rule's ID (14001 to 14103), ``name``
    its name ("gltf-payload"), ``path`` the JSON pointer of the place in the asset."""

    def __init__(self, code, name, section, offset, message, path=""):
        self.path = path
        super().__init__(code, name, section, offset, message)
        if path:
            self.args = ("%s: %s" % (path, self.args[0]),)


def error_class(code):
    """The Error subclass that stands for a vff::Code."""
    if 1000 <= code < 2000:
        return IoError
    if 2000 <= code < 9000:
        return InvalidFileError
    if 11000 <= code < 12000:
        return SceneError
    if 14000 <= code < 15000:
        return GltfError
    if code >= 10000:
        return MeshError
    if code in (9001, 9002):
        return InvalidArgumentError
    if code == 9005:
        return UnsupportedError
    return OperationError


def make_error(code, name, section, offset, message):
    """The exception for one libvff Error (called by the extension)."""
    return error_class(code)(code, name, section, offset, message)
