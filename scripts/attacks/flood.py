"""Issue 49, item 1: Moves without an Advance to a lock-step world with latency
emulation, and the daemon's resident memory before, after and after an Advance.

    python3 scripts/attacks/flood.py target/release/pushlearn-sim [MOVES]

Raw frames over a localhost socket; needs nothing but Python. Stops the
daemon it started.
"""

import socket
import struct
import subprocess
import sys
import time

from wire import varint

sim = sys.argv[1]
moves = int(sys.argv[2]) if len(sys.argv) > 2 else 2_000_000
daemon = subprocess.Popen(
    [sim, "serve", "--mode", "lockstep", "--latency-max", "2", "--port", "0"],
    stdout=subprocess.PIPE,
    stderr=subprocess.DEVNULL,
    text=True,
)
assert daemon.stdout is not None
port = next(
    int(line.rsplit(":", 1)[1].split()[0])
    for line in daemon.stdout
    if "127.0.0.1:" in line
)


def rss_mb() -> int:
    with open(f"/proc/{daemon.pid}/status") as status:
        kb = next(int(line.split()[1]) for line in status if line.startswith("VmRSS"))
    return kb // 1024


def frame(seq: int, payload: bytes) -> bytes:
    message = b"\x08" + varint(seq) + payload
    return struct.pack(">I", len(message)) + message


MOVE = b"\x12\x0d\x08\x01\x12\x09\x09" + struct.pack("<d", 0.1)
ADVANCE = b"\x1a\x02\x20\x01"
try:
    print("daemon RSS before:", rss_mb(), "MB")
    client = socket.create_connection(("127.0.0.1", port))
    batch = []
    sent = 0
    for seq in range(1, moves + 1):
        batch.append(frame(seq, MOVE))
        if len(batch) == 10_000 or seq == moves:
            try:
                client.sendall(b"".join(batch))
            except OSError as err:
                print(f"the world closed the connection after {sent} Moves ({err})")
                break
            sent, batch = seq, []
    time.sleep(2)
    print("daemon RSS after the flood:", rss_mb(), "MB")
    advancing = socket.create_connection(("127.0.0.1", port))
    advancing.sendall(frame(1, ADVANCE))
    time.sleep(2)
    print("daemon RSS after an Advance:", rss_mb(), "MB")
finally:
    daemon.terminate()
    daemon.wait()
