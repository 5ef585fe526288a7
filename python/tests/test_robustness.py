"""Bad input never crashes the interpreter: the fuzz regressions and damaged copies of
corpus logs through ``ulog.ULog`` and ``ulog.open`` give values or the package's (or
pyulog's) exceptions."""

import random

import ulog

ALLOWED = (ulog.ULogError, UnicodeDecodeError, RecursionError)


def exercise(data: bytes):
    import io

    for recover in (False, True):
        try:
            u = ulog.ULog(io.BytesIO(data), recover=recover)
            for d in u.data_list:
                for v in d.data.values():
                    v.sum()
        except ALLOWED:
            pass
    try:
        log = ulog.open(data)
    except ALLOWED:
        return
    for t in log.topics():
        table = log.table(t["name"], t["multi_id"])
        table.numpy()
    log.messages()
    log.analysis()


def test_fuzz_regressions(fuzz_regressions):
    files = [p for p in fuzz_regressions.rglob("*") if p.is_file()]
    assert files
    for p in files:
        exercise(p.read_bytes())


def test_damaged_copies_of_corpus_logs(corpus_log, capsys):
    data = corpus_log.read_bytes()[: 2 << 20]
    rng = random.Random(len(data))
    for _ in range(6):
        d = bytearray(data)
        for _ in range(20):
            d[rng.randrange(len(d))] = rng.randrange(256)
        exercise(bytes(d))
        exercise(bytes(d[: rng.randrange(len(d))]))
    capsys.readouterr()
