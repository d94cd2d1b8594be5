"""The run record and the paper's tables as the Python tools read them (schema:
docs/run_record.md); idmpc writes both from src/idmpc/experiment/.

- read_log(path, label): the per-step CSV log, columns t, q0.., v0.., u0.., [uc0..,] residual,
  update_ms[, x, y, z, x_ref, y_ref, z_ref]
- read_summary(path): the JSON summary, checked for the schema version this module reads
- load_paper_tables(): the paper's Tables 1-3 from mjcf/paper_tables.json
"""
import csv
import json
import os

RUN_RECORD_SCHEMA = 1
HERE = os.path.dirname(os.path.abspath(__file__))
PAPER_TABLES = os.path.join(HERE, "..", "mjcf", "paper_tables.json")


class LogError(Exception):
    """A log that cannot be read; the message names the file."""


class Log:
    """Columns of one closed-loop log."""

    def __init__(self, path, label):
        self.path = path
        self.label = label
        self.n = 0
        self.t = []
        self.q = []  # q[j] is the time series of joint j
        self.v = []
        self.u = []
        self.residual = []
        self.update_ms = []
        self.frame = []      # with a frame target: [x, y, z] per row, and its target
        self.frame_ref = []


FRAME_COLUMNS = ["x", "y", "z", "x_ref", "y_ref", "z_ref"]


def expected_header(n, commanded, frame=False):
    return (["t"] + [f"q{j}" for j in range(n)] + [f"v{j}" for j in range(n)]
            + [f"u{j}" for j in range(n)] + ([f"uc{j}" for j in range(n)] if commanded else [])
            + ["residual", "update_ms"] + (FRAME_COLUMNS if frame else []))


def read_log(path, label):
    """Reads and validates one log; raises LogError naming the file."""
    try:
        with open(path, newline="") as f:
            rows = list(csv.reader(f))
    except OSError as err:
        raise LogError(f"cannot read log '{path}': {err.strerror}") from None
    if not rows:
        raise LogError(f"log '{path}' is empty (expected a header t,q0,...,residual,update_ms)")
    header = [name.strip() for name in rows[0]]
    ncols = len(header)
    commanded = "uc0" in header
    frame = header[-len(FRAME_COLUMNS):] == FRAME_COLUMNS
    n = (ncols - 3 - (len(FRAME_COLUMNS) if frame else 0)) // (4 if commanded else 3)
    if n < 1 or header != expected_header(n, commanded, frame):
        shown = ",".join(header[:8]) + (",..." if ncols > 8 else "")
        raise LogError(f"log '{path}' has a malformed header: expected "
                       "t,q0..q{n-1},v0..v{n-1},u0..u{n-1}[,uc0..uc{n-1}],residual,update_ms"
                       "[,x,y,z,x_ref,y_ref,z_ref] with n >= 1, "
                       f"got '{shown}' ({ncols} columns)")
    log = Log(path, label)
    log.n = n
    log.q = [[] for _ in range(n)]
    log.v = [[] for _ in range(n)]
    log.u = [[] for _ in range(n)]
    for lineno, row in enumerate(rows[1:], start=2):
        if not row or all(not cell.strip() for cell in row):
            continue
        if len(row) != ncols:
            raise LogError(f"log '{path}' line {lineno}: expected {ncols} values, got {len(row)}")
        try:
            values = [float(cell) for cell in row]
        except ValueError:
            raise LogError(f"log '{path}' line {lineno}: not a number in '{','.join(row)[:80]}'") \
                from None
        log.t.append(values[0])
        for j in range(n):
            log.q[j].append(values[1 + j])
            log.v[j].append(values[1 + n + j])
            log.u[j].append(values[1 + 2 * n + j])
        end = len(values) - (len(FRAME_COLUMNS) if frame else 0)
        log.residual.append(values[end - 2])
        log.update_ms.append(values[end - 1])
        if frame:
            log.frame.append(values[end:end + 3])
            log.frame_ref.append(values[end + 3:end + 6])
    if not log.t:
        raise LogError(f"log '{path}' has a header but no data rows")
    return log


def read_summary(path):
    """The JSON summary of a run; raises LogError for another schema version."""
    try:
        with open(path, encoding="utf-8") as fh:
            s = json.load(fh)
    except (OSError, ValueError) as err:
        raise LogError(f"cannot read run summary '{path}': {err}") from None
    if s.get("schema") != RUN_RECORD_SCHEMA:
        raise LogError(f"run summary '{path}': schema {s.get('schema')!r}, these tools read {RUN_RECORD_SCHEMA}")
    return s


def load_paper_tables(path=PAPER_TABLES):
    """The paper's cells: dicts with table, model, n, formulation, N, kmax, ms, mark."""
    with open(path, encoding="utf-8") as fh:
        return json.load(fh)["cells"]
