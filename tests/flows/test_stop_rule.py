"""When a search stops asking for trials (:class:`flows.search.StopRule`), without a store."""

from flows.search import MAX_REPEATS_IN_ROW, StopRule, committed_seconds


def test_committed_seconds_are_spent_plus_the_running_trials_expected():
    assert committed_seconds(10.0, 2.5, 0) == 10.0
    assert committed_seconds(10.0, 2.5, 3) == 17.5


def test_the_budget_stops_the_search_and_it_never_asks_again():
    rule = StopRule(slots=2)
    assert rule.asks(lambda: True)
    assert not rule.asks(lambda: False)
    assert not rule.asks(lambda: True)  # once refused, never again
    assert rule.stopped


def test_a_slot_of_failures_in_a_row_stops_it_before_the_budget_is_asked():
    rule = StopRule(slots=2)
    rule.told(repeat=False, failed=True)
    assert rule.asks(lambda: True)
    rule.told(repeat=False, failed=False)  # a success resets the count
    rule.told(repeat=False, failed=True)
    assert rule.asks(lambda: True)
    rule.told(repeat=False, failed=True)

    def budget() -> bool:
        raise AssertionError("the budget is not weighed once the failures stop the search")

    assert not rule.asks(budget)


def test_repeats_in_a_row_stop_it():
    rule = StopRule(slots=1)
    for _ in range(MAX_REPEATS_IN_ROW - 1):
        rule.told(repeat=True, failed=False)
    assert rule.asks(lambda: True)
    rule.told(repeat=False, failed=False)
    for _ in range(MAX_REPEATS_IN_ROW):
        rule.told(repeat=True, failed=False)
    assert not rule.asks(lambda: True)
