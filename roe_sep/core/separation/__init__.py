"""Separation designs: the double impulse (SPL ejection + blind drift-stop, seeds 000/002 Eqs. 6-21, Tables 1-2)
and the multi-impulse scheme with purely tangential carrier burns (seed 001 Sec. 3).
"""
