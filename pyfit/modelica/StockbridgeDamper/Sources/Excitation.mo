within StockbridgeDamper.Sources;
block Excitation "Built-in excitation signal: sine, linear or logarithmic sweep, optionally with constant velocity amplitude"
  parameter Integer kind = 0 "0: off; 1: sine at f_start; 2: linear sweep; 3: logarithmic sweep; 4: linear sweep and 5: logarithmic sweep with constant velocity amplitude (y is then a displacement in m)";
  parameter Real amplitude = 1 "Amplitude of y (kinds 1-3, unit of y) or velocity amplitude in m/s (kinds 4-5)";
  parameter Real f_start(unit="Hz") = 1 "Sine frequency, or start frequency of a sweep (> 0 for kinds 3-5)";
  parameter Real f_end(unit="Hz") = 60 "End frequency of a sweep; the frequency is held at f_end afterwards";
  parameter Real rate(unit="Hz/s") = 0.5 "Rate of a linear sweep";
  parameter Real octaves_per_minute(unit="1/min") = 1 "Rate of a logarithmic sweep";
  parameter Real t_ramp(unit="s") = 0 "Duration of a C2-smooth amplitude ramp from zero (0: none)";
  output Real y "Excitation signal";
  Real f(unit="Hz") "Instantaneous frequency";
  Real theta(unit="rad") "Phase";
  Real env(unit="1") "Amplitude envelope (ramp)";
  Real t_lin(unit="s") "Time clipped to the end of the linear sweep";
  Real t_log(unit="s") "Time clipped to the end of the logarithmic sweep";
  Real theta_lin(unit="rad") "Phase of the linear sweep";
  Real theta_log(unit="rad") "Phase of the logarithmic sweep";
  Real tr(unit="1") "Normalised ramp time";
protected
  parameter Real pi = 3.14159265358979323846 "Ratio of circumference to diameter";
  parameter Real k_oct(unit="1/s") = octaves_per_minute/60 "Logarithmic sweep rate in octaves per second";
  parameter Real T_lin(unit="s") = (f_end - f_start)/rate "Duration of the linear sweep";
  parameter Real T_log(unit="s") = log(f_end/f_start)/(log(2)*k_oct) "Duration of the logarithmic sweep";
equation
  t_lin = if time < T_lin then time else T_lin;
  t_log = if time < T_log then time else T_log;
  theta_lin = 2*pi*(f_start*t_lin + 0.5*rate*t_lin^2 + f_end*(time - t_lin));
  theta_log = 2*pi*(f_start*(2^(k_oct*t_log) - 1)/(k_oct*log(2)) + f_end*(time - t_log));
  f = if kind == 1 then f_start else if kind == 2 or kind == 4 then f_start + rate*t_lin else f_start*2^(k_oct*t_log);
  theta = if kind == 1 then 2*pi*f_start*time else if kind == 2 or kind == 4 then theta_lin else theta_log;
  tr = if t_ramp > 0 and time < t_ramp then time/t_ramp else 1;
  env = tr^3*(10 - 15*tr + 6*tr^2);
  y = if kind == 0 then 0 else if kind <= 3 then amplitude*env*sin(theta) else amplitude/(2*pi*f)*env*sin(theta);
end Excitation;
