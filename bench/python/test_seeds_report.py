"""Unit tests of the benchmark's interaction-to-success figures (seeds_report.to_success,
seeds_report.median_to_success). Run: python3 -m unittest bench/python/test_seeds_report.py
(rig/tests/systems.rs does)."""

import sys
import unittest
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from seeds_report import median_to_success, to_success  # noqa: E402


class ToSuccess(unittest.TestCase):
    def test_first_success_and_the_success_held_to_the_end(self):
        evals = [(10, False), (20, True), (30, False), (40, True), (50, True)]
        self.assertEqual(to_success(evals), (20, 40))

    def test_a_run_whose_last_evaluation_fails_never_holds(self):
        self.assertEqual(to_success([(10, True), (20, True), (30, False)]), (10, None))

    def test_a_run_that_never_succeeds(self):
        self.assertEqual(to_success([(10, False), (20, False)]), (None, None))
        self.assertEqual(to_success([]), (None, None))

    def test_success_from_the_first_evaluation_on(self):
        self.assertEqual(to_success([(5, True), (10, True)]), (5, 5))


class MedianToSuccess(unittest.TestCase):
    def test_a_seed_that_never_got_there_counts_as_later_than_any(self):
        self.assertEqual(median_to_success([300, None, 100, 200, None]), 300)

    def test_none_when_the_median_seed_never_got_there(self):
        self.assertIsNone(median_to_success([None, None, 100, None, 50]))

    def test_an_even_count_averages_the_middle_two_or_has_none(self):
        self.assertEqual(median_to_success([40, 10, 20, 30]), 25)
        self.assertIsNone(median_to_success([10, 20, None, None]))

    def test_zero_is_a_time_not_a_failure(self):
        self.assertEqual(median_to_success([0, 0, None]), 0)
        self.assertIsNone(median_to_success([]))


if __name__ == "__main__":
    unittest.main()
