"""Issue 49, items 2 and 3: 64 silent connections and 800 more to
`pushlearn serve-learner --listen`; its threads and descriptors, and whether a
driver is served now and after WAIT seconds (default 65: past the idle timeout).

    WAIT=65 python3 scripts/attacks/learner-connections.py target/release/pushlearn [FLAGS…]

Stops the daemon it started.
"""

import os
import socket
import struct
import subprocess
import sys
import time

daemon = subprocess.Popen(
    [sys.argv[1], "serve-learner", "--listen", "0", *sys.argv[2:]],
    stdout=subprocess.PIPE,
    stderr=subprocess.DEVNULL,
    text=True,
)
assert daemon.stdout is not None
port = int(daemon.stdout.readline().rsplit(":", 1)[1])
wait = float(os.environ.get("WAIT", "65"))
START = b"\x08\x01\x12\x0f\x08\x01\x12\x09push-task\x18\x64"


def threads() -> int:
    return len(os.listdir(f"/proc/{daemon.pid}/task"))


def descriptors() -> int:
    return len(os.listdir(f"/proc/{daemon.pid}/fd"))


def a_driver() -> str:
    driver = socket.create_connection(("127.0.0.1", port))
    driver.settimeout(5)
    driver.sendall(struct.pack(">I", len(START)) + START)
    try:
        reply = driver.recv(4096)
    except OSError:
        return "no answer"
    return (
        "refused (too many connections)" if b"too many" in reply else "served (Hello)"
    )


try:
    silent = [socket.create_connection(("127.0.0.1", port)) for _ in range(64)]
    more = [socket.create_connection(("127.0.0.1", port)) for _ in range(800)]
    time.sleep(1)
    print(
        f"64 silent + 800 more connections: {threads()} threads, {descriptors()} descriptors"
    )
    for connection in more:
        connection.close()
    print("a driver now:", a_driver())
    time.sleep(wait)
    print(f"a driver after {wait:g} s:", a_driver(), f"({threads()} threads)")
finally:
    daemon.terminate()
    daemon.wait()
