from pipeline.chain.metrics import SpikeMetrics
from pipeline.run.entries import ResultEntry, decode_result_entry, encode_result_entry
from pipeline.run.records import Charge


def test_paid_seconds_and_their_point_round_trip_and_older_entries_have_none():
    metrics = SpikeMetrics(1.0, 0.0, 0.0, 2.0, 3.0, 4.0)
    paid = {Charge.OWN: {"train_ffnn": 1.5}, Charge.SHARED: {"load": 0.25, "setup": 0.75}}
    entry = ResultEntry({"ffnn": [0.5, 0.5]}, {"train_ffnn": 1.5, "load": 0.25}, metrics, paid=paid)
    values, attrs = encode_result_entry(entry)
    assert attrs["paid_seconds"] == {
        "own": {"train_ffnn": 1.5},
        "shared": {"load": 0.25, "setup": 0.75},
    }
    assert decode_result_entry(values, attrs).paid == paid
    del attrs["paid_seconds"]  # as written before paid seconds were kept
    assert decode_result_entry(values, attrs).paid is None
