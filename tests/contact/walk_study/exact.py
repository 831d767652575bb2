from math import *
def exact_stops(f0, omega, phase, t_end, mu, g):
    fs = mu*g; stops=[]; t0=0.0; x0=0.0; h=1e-5
    F=lambda t: f0*sin(omega*t+phase)
    while True:
        t=t0
        while t<t_end and abs(F(t))<=fs: t+=h
        if t>=t_end: break
        lo,hi=max(t-h,t0),t
        if t>t0:
            for i in range(60):
                m=(lo+hi)/2
                if abs(F(m))<=fs: lo=m
                else: hi=m
        ts=hi if t>t0 else t0
        s=1.0 if F(ts)>0 else -1.0
        v=lambda tt: f0/omega*(cos(omega*ts+phase)-cos(omega*tt+phase)) - s*fs*(tt-ts)
        x=lambda tt: x0 + f0/omega*((tt-ts)*cos(omega*ts+phase) - (sin(omega*tt+phase)-sin(omega*ts+phase))/omega) - 0.5*s*fs*(tt-ts)**2
        te=ts+h
        while te<t_end and v(te)*s>0: te+=h
        if te>=t_end: break
        lo,hi=te-h,te
        for i in range(60):
            m=(lo+hi)/2
            if v(m)*s>0: lo=m
            else: hi=m
        t0=hi; x0=x(hi); stops.append((t0,x0))
    return stops
import sys
mu=float(sys.argv[1]) if len(sys.argv)>1 else 0.8
for s in exact_stops(1.02*mu*9.81,1.0,pi/2,8.0,mu,9.81): print("%.5f %.7e"%s)
