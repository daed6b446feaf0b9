"""Numerical experiments that set the model beside the paper."""
