"""Writers and readers of mgn's file formats. Every file is written atomically."""

from mgn.base.atomic import atomic_dir, atomic_write_bytes, atomic_write_text
from mgn.io.model_folder import ModelFolder, read_model_folder, write_model_folder, write_tote

__all__ = [
    "ModelFolder",
    "atomic_dir",
    "atomic_write_bytes",
    "atomic_write_text",
    "read_model_folder",
    "write_model_folder",
    "write_tote",
]
