"""Issue 49, item 11: what pushlearn serve-learner answers to Starts that break
the protocol page's rules, and to a SetTarget without x ("reply": a Hello
or TargetReply; "Error": the refusal the page promises).

    python3 scripts/attacks/starts.py target/release/pushlearn
"""

import socket
import struct
import subprocess
import sys

from wire import length_delimited, varint

bin_ = sys.argv[1]
p = subprocess.Popen(
    [bin_, "serve-learner", "--listen", "0"],
    stdout=subprocess.PIPE,
    stderr=subprocess.DEVNULL,
    text=True,
)
port = int(p.stdout.readline().rsplit(":", 1)[1])


def req(seq, field, body):
    m = b"\x08" + varint(seq) + length_delimited(field, body)
    return struct.pack(">I", len(m)) + m


def start(version, task, rate):
    return req(
        1,
        2,
        b"\x08"
        + varint(version)
        + length_delimited(2, task.encode())
        + b"\x18"
        + varint(rate),
    )


def answer(*frames):
    s = socket.create_connection(("127.0.0.1", port))
    s.settimeout(5)
    s.sendall(b"".join(frames))
    data = b""
    try:
        while d := s.recv(65536):
            data += d
    except OSError:
        pass
    kinds = []
    while len(data) >= 4:
        n = struct.unpack(">I", data[:4])[0]
        body = data[4 : 4 + n]
        data = data[4 + n :]
        kinds.append(
            "Error"
            if b"\x3a" in body[:4]
            else ("Hello" if b"\x1a" in body[:4] else "reply")
        )
    return kinds or ["closed, no reply"]


ok = start(1, "push-task", 100)
bye = req(1, 11, b"")
target_no_x = req(
    2,
    8,
    b"\x10\x0f" + b"\x21" + struct.pack("<d", 0.5) + b"\x29" + struct.pack("<d", 0.0),
)
cases = {
    "first request Bye": [bye],
    "version 99": [start(99, "push-task", 100)],
    "rate 0": [start(1, "push-task", 0)],
    "rate 7": [start(1, "push-task", 7)],
    "rate 2^32-1": [start(1, "push-task", 2**32 - 1)],
    "1000-char task": [start(1, "x" * 1000, 100)],
    "SetTarget without x": [ok, target_no_x],
}
for name, frames in cases.items():
    print(f"{name}: {answer(*frames)}")
p.terminate()
