"""Loading a model.pt (sim4cv.driving_train's weights and settings) that
someone else may have written: its pickles are scanned before anything is
unpickled, and a file that refers to anything but tensors, numbers, strings
and containers is refused unloaded (docs/driving.md, "Bad models and maps").
"""

import io
import pickletools
import zipfile

import torch


class WeightsError(RuntimeError):
    """A model.pt refused; the message names the file and why."""


# The only globals a model.pt of `_save` refers to: torch's tensor rebuilding and ordered dicts.
ALLOWED_GLOBALS = {"collections OrderedDict", "torch._utils _rebuild_tensor_v2", "torch._utils _rebuild_parameter"}


def check_pickle(data: bytes, name: str) -> None:
    """Refuses a pickle that imports anything but ALLOWED_GLOBALS and torch's
    storages (os.system, builtins.eval, ...): what loading it could run.
    Scanned before unpickling, since torch 1.13's weights_only=True cannot
    read the floats a model.pt's settings hold, and its torch.load ignores
    a restricted pickle_module."""
    try:
        for op, arg, _ in pickletools.genops(data):
            if op.name in ("GLOBAL", "INST"):
                module, _, attribute = str(arg).partition(" ")
                if str(arg) not in ALLOWED_GLOBALS and not (module == "torch" and attribute.endswith("Storage")):
                    raise WeightsError("%s: refers to %s.%s; a model.pt holds only tensors, numbers, strings and "
                                       "containers (not loaded: it could run code)" % (name, module, attribute))
            elif op.name in ("STACK_GLOBAL", "EXT1", "EXT2", "EXT4", "OBJ"):
                raise WeightsError("%s: uses the pickle instruction %s, which torch.save never writes (not loaded: "
                                   "it could run code)" % (name, op.name))
    except (ValueError, EOFError) as e:  # pickletools' complaints about a broken stream
        raise WeightsError("%s: a damaged model.pt (%s)" % (name, e)) from None


def load_saved(source, name: str = "") -> dict:
    """A model.pt's contents (a path, or a file object and its name for
    messages), loaded only after check_pickle passed its data.pkl."""
    name = name or str(source)
    if hasattr(source, "read"):
        data = source.read()
    else:
        with open(source, "rb") as f:
            data = f.read()
    try:
        with zipfile.ZipFile(io.BytesIO(data)) as z:
            pickles = [n for n in z.namelist() if n.endswith(".pkl")]
            if not pickles:
                raise WeightsError("%s: no pickled data inside; not a model.pt of `train`" % name)
            for n in pickles:
                check_pickle(z.read(n), name)
    except zipfile.BadZipFile:
        raise WeightsError("%s: not a model.pt of `train` (torch's zip format; empty or truncated?)" % name) from None
    return torch.load(io.BytesIO(data), map_location="cpu")
