"""Issue 49, item 2: 64 silent connections to a lock-step pushlearn-sim, and
whether a client gets its Hello now and after WAIT seconds.

    python3 scripts/attacks/world-silent.py target/release/pushlearn-sim 62 [FLAGS…]
"""

import socket
import subprocess
import sys
import time

sim, wait = sys.argv[1], float(sys.argv[2])
extra = sys.argv[3:]
p = subprocess.Popen(
    [sim, "serve", "--mode", "lockstep", "--port", "0", *extra],
    stdout=subprocess.PIPE,
    stderr=subprocess.DEVNULL,
    text=True,
)
port = next(int(l.rsplit(":", 1)[1].split()[0]) for l in p.stdout if "127.0.0.1:" in l)
silent = [socket.create_connection(("127.0.0.1", port)) for _ in range(64)]


def client():
    s = socket.create_connection(("127.0.0.1", port))
    s.settimeout(5)
    d = s.recv(4096)
    return (
        "Hello"
        if b"one_block" in d
        else ("TOO_MANY_CLIENTS" if b"too many" in d else repr(d[:40]))
    )


time.sleep(1)
print("now:", client())
time.sleep(wait)
print(f"after {wait:g} s:", client())
p.terminate()
