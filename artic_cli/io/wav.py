"""WAV files: 16-bit PCM written atomically, and read back as floats."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from scipy.io import wavfile

from ..errors import ArticError
from .store import atomic_path


def write_wav(path: Path | str, audio) -> Path:
    """16-bit PCM WAV, written through a temporary file and a rename."""
    path = Path(path)
    pcm = np.round(np.clip(audio.samples, -1, 1) * 32767).astype(np.int16)
    with atomic_path(path, ".wav") as tmp:
        wavfile.write(tmp, audio.sample_rate_hz, pcm)
    return path


def read_wav(path: Path | str) -> tuple[np.ndarray, int]:
    """Samples (float, -1..1, the first channel) and the rate of a WAV file; a missing or damaged file is
    one error naming the fix."""
    path = Path(path)
    if not path.is_file():
        raise ArticError(f"WAV file not found: {path}; give an existing file (rerun 'artic synthesize')")
    try:
        rate, data = wavfile.read(path)
    except (ValueError, OSError, EOFError):
        raise ArticError(f"{path} is not a readable WAV file (corrupted or truncated); rerun 'artic synthesize'") from None
    data = np.asarray(data)
    if data.ndim > 1:
        data = data[:, 0]
    scale = float(np.iinfo(data.dtype).max) if np.issubdtype(data.dtype, np.integer) else 1.0
    return data.astype(float) / scale, int(rate)
