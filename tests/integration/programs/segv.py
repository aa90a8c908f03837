"""Dies of a real segmentation fault (a read of address 0), as a crashing C++ node does."""

import ctypes

print("about to crash", flush=True)
ctypes.string_at(0)
