"""Writes the npz fixtures of reference/src/tests.rs with numpy (run once; the
files are committed): members present, absent as pickled None, empty, and a
non-None object array."""
import numpy as np

inf = np.inf
P = np.array([[4.0, 1.0, 0.0], [1.0, 3.0, 0.5], [0.0, 0.5, 2.0]])
q = np.array([1.0, -2.0, 0.5])
G = np.array([[1.0, 1.0, 1.0], [-1.0, 2.0, 0.0]])
h = np.array([1.0, 2.0])
A = np.asfortranarray(np.array([[1.0, -1.0, 2.0], [0.0, 1.0, 1.0]]))
b = np.array([0.5, 0.3])
lb = np.array([-inf, -1.0, 0.0])
ub = np.array([1.0, inf, 2.0])
np.savez("full.npz", P=P, q=q, G=G, h=h, A=A, b=b, lb=lb, ub=ub)
np.savez("none.npz", P=P, q=q, G=None, h=None, A=None, b=None, lb=None, ub=None)
np.savez("empty.npz", P=P, q=q, G=np.zeros((0, 3)), h=np.zeros(0),
         A=np.empty((0, 3)), b=np.empty(0), lb=np.empty(0), ub=ub)
np.savez("half_pair.npz", P=P, q=q, G=None, h=h)
np.savez("object.npz", P=P, q=q, lb=np.array([1.0, 2.0, 3.0], dtype=object))
